#include "core/common/option_table.h"

#include <cmath>
#include <sstream>

namespace satmesh {

std::string OptionValueText(const OptionValue& v) {
  if (const bool* b = std::get_if<bool>(&v)) return *b ? "true" : "false";
  if (const int* i = std::get_if<int>(&v)) return std::to_string(*i);
  std::ostringstream out;
  out << std::get<double>(v);
  return out.str();
}

std::string OptionRangeText(const OptionRange& range) {
  const auto& [min, max, min_exclusive, max_exclusive] = range;
  std::ostringstream text;
  if (min && max) {
    text << (min_exclusive ? "(" : "[") << OptionValueText(*min) << ", " << OptionValueText(*max)
         << (max_exclusive ? ")" : "]");
  } else if (min) {
    text << (min_exclusive ? "> " : ">= ") << OptionValueText(*min);
  } else if (max) {
    text << (max_exclusive ? "< " : "<= ") << OptionValueText(*max);
  }
  return text.str();
}

std::string CheckOptionRange(std::string_view name, const OptionRange& range,
                             const OptionValue& v) {
  if (std::holds_alternative<bool>(v)) return "";
  const double x = std::holds_alternative<int>(v) ? std::get<int>(v) : std::get<double>(v);
  const auto& [min, max, min_exclusive, max_exclusive] = range;
  const bool above_min = !min || (min_exclusive ? x > *min : x >= *min);
  const bool below_max = !max || (max_exclusive ? x < *max : x <= *max);
  if (above_min && below_max && std::isfinite(x)) return "";
  const std::string range_text = OptionRangeText(range);
  std::ostringstream message;
  message << name << " must be " << (min && max ? "in " : "") << range_text << ", got "
          << OptionValueText(v);
  return message.str();
}

}  // namespace satmesh
