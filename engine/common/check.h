#pragma once
// PLANTSCALE_CHECK: programming errors (broken invariants), never bad data.
// Bad data and I/O failures use the typed exceptions in options.h instead.

#include <sstream>
#include <stdexcept>
#include <string>

namespace plantscale {

class InternalError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

[[noreturn]] inline void FailCheck(const char* condition, const char* file, int line,
                                   const std::string& message) {
  std::ostringstream out;
  out << file << ":" << line << ": check failed: " << condition;
  if (!message.empty()) out << " (" << message << ")";
  throw InternalError(out.str());
}

}  // namespace plantscale

#define PLANTSCALE_CHECK(condition, message)                                              \
  do {                                                                                    \
    if (!(condition)) ::plantscale::FailCheck(#condition, __FILE__, __LINE__, (message)); \
  } while (false)
