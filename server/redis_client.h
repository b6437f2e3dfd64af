#pragma once
// A small synchronous Redis client over hiredis (kept out of this header): one connection,
// argv commands, replies as plain values. Not thread-safe: one connection per thread.
#include <memory>
#include <string>
#include <vector>

namespace satmesh::server {

// redis://HOST[:PORT][/DB]; PORT defaults to 6379, DB to 0.
struct RedisAddress {
  std::string host;
  int port = 6379;
  int db = 0;
};
// Throws Error{kInvalidArgument} naming the problem.
RedisAddress ParseRedisUrl(const std::string& url);

struct RedisReply {
  enum class Type { kNil, kString, kInteger, kArray, kStatus };
  Type type = Type::kNil;
  std::string str;            // kString, kStatus
  long long integer = 0;      // kInteger
  std::vector<RedisReply> elements;  // kArray
  bool nil() const { return type == Type::kNil; }
};

class RedisConnection {
 public:
  // Connects (and SELECTs the DB) lazily, on the first command. timeout_s bounds every
  // command's socket wait (a blocking XREADGROUP's BLOCK must stay below it).
  explicit RedisConnection(RedisAddress address, double timeout_s = 10);
  ~RedisConnection();
  RedisConnection(const RedisConnection&) = delete;
  RedisConnection& operator=(const RedisConnection&) = delete;
  // Runs one command. Throws Error{kIo} when Redis cannot be reached or answers with an
  // error (its message); after a connection failure the next command reconnects.
  RedisReply Command(const std::vector<std::string>& argv);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace satmesh::server
