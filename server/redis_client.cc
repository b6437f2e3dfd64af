#include "server/redis_client.h"

#include <hiredis/hiredis.h>

#include <cmath>

#include "core/common/error.h"

namespace satmesh::server {
namespace {

RedisReply Convert(const redisReply* r) {
  RedisReply out;
  switch (r->type) {
    case REDIS_REPLY_STRING:
      out.type = RedisReply::Type::kString;
      out.str.assign(r->str, r->len);
      break;
    case REDIS_REPLY_STATUS:
      out.type = RedisReply::Type::kStatus;
      out.str.assign(r->str, r->len);
      break;
    case REDIS_REPLY_INTEGER:
      out.type = RedisReply::Type::kInteger;
      out.integer = r->integer;
      break;
    case REDIS_REPLY_ARRAY:
      out.type = RedisReply::Type::kArray;
      for (size_t i = 0; i < r->elements; ++i) out.elements.push_back(Convert(r->element[i]));
      break;
    default:
      break;  // nil
  }
  return out;
}

}  // namespace

RedisAddress ParseRedisUrl(const std::string& url) {
  const std::string scheme = "redis://";
  SATMESH_CHECK(url.rfind(scheme, 0) == 0, ErrorCode::kInvalidArgument,
                "queue: '" + url + "' is not redis://HOST[:PORT][/DB]");
  std::string rest = url.substr(scheme.size());
  RedisAddress a;
  const size_t slash = rest.find('/');
  try {
    if (slash != std::string::npos) {
      const std::string db = rest.substr(slash + 1);
      if (!db.empty()) {
        size_t used = 0;
        a.db = std::stoi(db, &used);
        SATMESH_CHECK(used == db.size() && a.db >= 0, ErrorCode::kInvalidArgument, "bad DB");
      }
      rest = rest.substr(0, slash);
    }
    const size_t colon = rest.rfind(':');
    if (colon != std::string::npos) {
      const std::string port = rest.substr(colon + 1);
      size_t used = 0;
      a.port = std::stoi(port, &used);
      SATMESH_CHECK(used == port.size() && a.port > 0 && a.port < 65536, ErrorCode::kInvalidArgument, "bad port");
      rest = rest.substr(0, colon);
    }
  } catch (const std::exception&) {
    ThrowError(ErrorCode::kInvalidArgument, "queue: '" + url + "' is not redis://HOST[:PORT][/DB]");
  }
  SATMESH_CHECK(!rest.empty(), ErrorCode::kInvalidArgument, "queue: '" + url + "' names no host");
  a.host = rest;
  return a;
}

struct RedisConnection::Impl {
  RedisAddress address;
  double timeout_s;
  redisContext* context = nullptr;

  void Close() {
    if (context) redisFree(context);
    context = nullptr;
  }
  timeval Timeout() const {
    return timeval{long(timeout_s), long((timeout_s - std::floor(timeout_s)) * 1e6)};
  }
  void Connect() {
    const std::string where = address.host + ":" + std::to_string(address.port);
    context = redisConnectWithTimeout(address.host.c_str(), address.port, Timeout());
    if (!context || context->err) {
      const std::string why = context ? context->errstr : "out of memory";
      Close();
      ThrowError(ErrorCode::kIo, "redis " + where + ": cannot connect: " + why);
    }
    redisSetTimeout(context, Timeout());
    if (address.db != 0) Run({"SELECT", std::to_string(address.db)});
  }
  RedisReply Run(const std::vector<std::string>& argv) {
    std::vector<const char*> args;
    std::vector<size_t> lengths;
    for (const auto& a : argv) args.push_back(a.data()), lengths.push_back(a.size());
    auto* reply = static_cast<redisReply*>(redisCommandArgv(context, int(args.size()), args.data(), lengths.data()));
    if (!reply) {
      const std::string why = context->errstr;
      Close();
      ThrowError(ErrorCode::kIo, "redis " + argv[0] + ": " + why);
    }
    if (reply->type == REDIS_REPLY_ERROR) {
      const std::string why(reply->str, reply->len);
      freeReplyObject(reply);
      ThrowError(ErrorCode::kIo, "redis " + argv[0] + ": " + why);
    }
    RedisReply out = Convert(reply);
    freeReplyObject(reply);
    return out;
  }
};

RedisConnection::RedisConnection(RedisAddress address, double timeout_s)
    : impl_(std::make_unique<Impl>()) {
  impl_->address = std::move(address);
  impl_->timeout_s = timeout_s;
}

RedisConnection::~RedisConnection() { impl_->Close(); }

RedisReply RedisConnection::Command(const std::vector<std::string>& argv) {
  SATMESH_CHECK(!argv.empty(), ErrorCode::kInternal, "redis: empty command");
  if (!impl_->context) impl_->Connect();
  return impl_->Run(argv);
}

}  // namespace satmesh::server
