#pragma once
// Validation of option structs (the Ceres habit: plain structs with defaults
// plus a check that explains what is wrong). Each options struct has
// `OptionErrors Validate() const`; keys are the struct's field names, so the
// app can name the YAML file and key a bad value came from.

#include <stdexcept>
#include <string>
#include <vector>

namespace plantscale {

struct OptionError {
  std::string key;     // e.g. "height_m", or "camera.height_m" once prefixed
  std::string reason;  // e.g. "must be > 0 (got -1.2)"
};
using OptionErrors = std::vector<OptionError>;

// Thrown when an options struct is invalid; what() lists every problem.
class InvalidOptionsError : public std::invalid_argument {
 public:
  InvalidOptionsError(std::string context, OptionErrors errors);
  const OptionErrors& errors() const { return errors_; }
  const std::string& context() const { return context_; }

 private:
  std::string context_;
  OptionErrors errors_;
};

// Thrown for bad input data (NaN odometry, malformed frames, ...).
class DataError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Helpers that append an error when a value is outside its domain.
void RequirePositive(OptionErrors& errors, const std::string& key, double value);
void RequireNonNegative(OptionErrors& errors, const std::string& key, double value);
void RequireInRange(OptionErrors& errors, const std::string& key, double value, double low,
                    double high, bool low_inclusive = true, bool high_inclusive = true);
void RequireFinite(OptionErrors& errors, const std::string& key, double value);

// Prefixes every key with `prefix.` (for nested option structs).
OptionErrors Prefixed(const std::string& prefix, OptionErrors errors);
// Throws InvalidOptionsError when `errors` is not empty.
void ThrowIfInvalid(const std::string& context, const OptionErrors& errors);

}  // namespace plantscale
