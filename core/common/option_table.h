#pragma once
// Options declared once (PDAL's habit): a table of OptionInfo, one per option of an options
// struct, says its wire name, the field it sets (its default is the field's initializer),
// its valid range and a one-line help. The struct's Check(), the wire parser (proto/), the
// CLI's --set and the JSON Schema are made from the table. Tables: RefineOptionTable()
// (core/refine/refine_options.h), TilingOptionTable() (core/tiling/job_spec.h).
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>
#include <vector>

#include "core/common/error.h"

namespace satmesh {

enum class OptionType { kBool, kInt, kDouble };
using OptionValue = std::variant<bool, int, double>;

struct OptionRange {  // a bound absent: none on that side
  std::optional<double> min, max;
  bool min_exclusive = false, max_exclusive = false;

  // Helpers for the tables: >= min, > min, [min, max], (min, max), (min, max], [min, max).
  static OptionRange AtLeast(double min) { return {min, std::nullopt, false, false}; }
  static OptionRange Above(double min) { return {min, std::nullopt, true, false}; }
  static OptionRange In(double min, double max) { return {min, max, false, false}; }
  static OptionRange Open(double min, double max) { return {min, max, true, true}; }
  static OptionRange AboveTo(double min, double max) { return {min, max, true, false}; }
  static OptionRange FromBelow(double min, double max) { return {min, max, false, true}; }
};

// A value as messages and the CLI write it: 2, 0.5, 1e-04, true.
std::string OptionValueText(const OptionValue& v);
// "[1, 20]", "(0, 1]", ">= 0", "> 0"; "" for none.
std::string OptionRangeText(const OptionRange& range);
// "" or "<name> must be in <range>, got <v>" (a number that is not finite is out of range).
std::string CheckOptionRange(std::string_view name, const OptionRange& range, const OptionValue& v);

struct NoNestedOptions {};

// One option of `Options`, or of its nested struct `Nested` (the member kNested of
// Options, e.g. RefineOptions::pairs), whose options the wire writes flat.
template <typename Options, typename Nested = NoNestedOptions, auto kNested = nullptr>
struct OptionInfo {
  using Field = std::conditional_t<std::is_same_v<Nested, NoNestedOptions>,
                                   std::variant<bool Options::*, int Options::*, double Options::*>,
                                   std::variant<bool Options::*, int Options::*, double Options::*,
                                                bool Nested::*, int Nested::*, double Nested::*>>;
  std::string_view name;  // wire name
  Field field;            // the field it sets
  OptionRange range;      // empty for booleans
  std::string_view help;  // one line; the schema's "description"

  OptionType type() const {
    return std::visit(
        [](auto member) {
          using T = std::remove_reference_t<decltype(Ref(std::declval<Options&>(), member))>;
          if constexpr (std::is_same_v<T, bool>)
            return OptionType::kBool;
          else if constexpr (std::is_same_v<T, int>)
            return OptionType::kInt;
          else
            return OptionType::kDouble;
        },
        field);
  }
  bool is_nested() const {  // a field of Nested
    return std::visit([](auto member) { return !IsOwn(member); }, field);
  }
  OptionValue Get(const Options& options) const {
    return std::visit([&](auto member) { return OptionValue(Ref(options, member)); }, field);
  }
  OptionValue Default() const {
    static const Options defaults{};  // the fields' initializers
    return Get(defaults);
  }
  // v must be of type() (an int is taken for a double option).
  void Set(Options* options, OptionValue v) const {
    std::visit(
        [&](auto member) {
          auto& target = Ref(*options, member);
          using T = std::remove_reference_t<decltype(target)>;
          if constexpr (std::is_same_v<T, double>)
            if (const int* i = std::get_if<int>(&v)) v = double(*i);
          SATMESH_CHECK(std::holds_alternative<T>(v), ErrorCode::kInternal,
                        std::string(name) + ": a value of another type");
          target = std::get<T>(v);
        },
        field);
  }
  std::string RangeText() const { return OptionRangeText(range); }
  std::string CheckValue(const Options& options) const {
    return CheckOptionRange(name, range, Get(options));
  }

 private:
  template <typename S, typename T>
  static constexpr bool IsOwn(T S::*) {
    return std::is_same_v<S, Options>;
  }
  template <typename O, typename T, typename S>  // O: Options or const Options
  static auto& Ref(O& options, T S::*member) {
    if constexpr (std::is_same_v<S, Options>)
      return options.*member;
    else
      return (options.*kNested).*member;
  }
};

// nullptr for a name not in the table.
template <typename Info>
const Info* FindOption(const std::vector<Info>& table, std::string_view name) {
  for (const Info& option : table)
    if (option.name == name) return &option;
  return nullptr;
}

// The first option of `options` out of its range, "" if none; with nested_only, only the
// nested struct's options.
template <typename Info, typename Options>
std::string CheckOptionRanges(const std::vector<Info>& table, const Options& options,
                              bool nested_only = false) {
  for (const Info& option : table) {
    if (nested_only && !option.is_nested()) continue;
    std::string problem = option.CheckValue(options);
    if (!problem.empty()) return problem;
  }
  return "";
}

}  // namespace satmesh
