#include "engine/common/options.h"

#include <cmath>
#include <sstream>

namespace plantscale {
namespace {

std::string Describe(const std::string& context, const OptionErrors& errors) {
  std::ostringstream out;
  out << context << ": invalid options";
  for (const OptionError& e : errors) out << "\n  " << e.key << ": " << e.reason;
  return out.str();
}

std::string Got(double value) {
  std::ostringstream out;
  out << " (got " << value << ")";
  return out.str();
}

}  // namespace

InvalidOptionsError::InvalidOptionsError(std::string context, OptionErrors errors)
    : std::invalid_argument(Describe(context, errors)),
      context_(std::move(context)),
      errors_(std::move(errors)) {}

void RequireFinite(OptionErrors& errors, const std::string& key, double value) {
  if (!std::isfinite(value)) errors.push_back({key, "must be a finite number" + Got(value)});
}

void RequirePositive(OptionErrors& errors, const std::string& key, double value) {
  if (!(std::isfinite(value) && value > 0.0)) errors.push_back({key, "must be > 0" + Got(value)});
}

void RequireNonNegative(OptionErrors& errors, const std::string& key, double value) {
  if (!(std::isfinite(value) && value >= 0.0)) {
    errors.push_back({key, "must be >= 0" + Got(value)});
  }
}

void RequireInRange(OptionErrors& errors, const std::string& key, double value, double low,
                    double high, bool low_inclusive, bool high_inclusive) {
  const bool above = low_inclusive ? value >= low : value > low;
  const bool below = high_inclusive ? value <= high : value < high;
  if (std::isfinite(value) && above && below) return;
  std::ostringstream out;
  out << "must be in " << (low_inclusive ? "[" : "(") << low << ", " << high
      << (high_inclusive ? "]" : ")") << Got(value);
  errors.push_back({key, out.str()});
}

OptionErrors Prefixed(const std::string& prefix, OptionErrors errors) {
  for (OptionError& e : errors) e.key = prefix + "." + e.key;
  return errors;
}

void ThrowIfInvalid(const std::string& context, const OptionErrors& errors) {
  if (!errors.empty()) throw InvalidOptionsError(context, errors);
}

}  // namespace plantscale
