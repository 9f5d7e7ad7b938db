#pragma once
// A real PostgreSQL + PostGIS server for gtests (tests/pg_server.sh): started
// in a temporary folder on 127.0.0.1 at a free port, stopped on destruction.
// When it cannot start, url() is empty and skip_reason() says why (tests
// then GTEST_SKIP with that reason).

#include <stdio.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <string>

#ifndef PLANTSCALE_PG_SERVER_SCRIPT
#error "PLANTSCALE_PG_SERVER_SCRIPT: path of tests/pg_server.sh"
#endif

namespace plantscale::maps::testing {

class PgServer {
 public:
  PgServer() {
    static std::atomic<int> counter{0};
    dir_ = (std::filesystem::temp_directory_path() /
            ("plantscale_pg_" + std::to_string(getpid()) + "_" + std::to_string(++counter)))
               .string();
    const std::string out = Run("start");
    if (status_ == 0 && out.rfind("postgresql://", 0) == 0) {
      url_ = out.substr(0, out.find('\n'));
    } else {
      skip_reason_ = "no PostgreSQL server: " + out;
    }
  }
  ~PgServer() { Run("stop"); }
  PgServer(const PgServer&) = delete;
  PgServer& operator=(const PgServer&) = delete;

  // postgresql://plantscale:plantscale@127.0.0.1:PORT/archive (PostGIS)
  const std::string& url() const { return url_; }
  // The same server and another database or password.
  std::string Url(const std::string& database, const std::string& password = "plantscale") const {
    std::string u = url_.substr(0, url_.rfind('/') + 1) + database;
    const size_t colon = u.find(':', std::string("postgresql://").size());
    return u.substr(0, colon + 1) + password + u.substr(u.find('@'));
  }
  const std::string& skip_reason() const { return skip_reason_; }

 private:
  std::string Run(const std::string& verb) {
    const std::string cmd = "bash '" PLANTSCALE_PG_SERVER_SCRIPT "' " + verb + " '" + dir_ + "' 2>&1";
    FILE* p = popen(cmd.c_str(), "r");
    std::string out;
    if (p == nullptr) return "cannot run " PLANTSCALE_PG_SERVER_SCRIPT;
    char buf[512];
    while (fgets(buf, sizeof buf, p) != nullptr) out += buf;
    const int st = pclose(p);
    status_ = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    return out;
  }

  std::string dir_, url_, skip_reason_;
  int status_ = -1;
};

}  // namespace plantscale::maps::testing
