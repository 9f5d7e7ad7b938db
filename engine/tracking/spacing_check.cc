#include "engine/tracking/spacing_check.h"

#include <cmath>
#include <cstdio>

namespace plantscale::tracking {

void SpacingCheck::Start(double prior_m, double prior_var, double scale_var) {
  prior_m_ = prior_m;
  prior_var_ = prior_var;
  scale_var_ = scale_var;
  current_.reset();
}

std::optional<SpacingMismatch> SpacingCheck::Check(double estimate_m, double variance) {
  current_.reset();
  if (chi2_ <= 0.0 || !(prior_var_ > 0.0) || !std::isfinite(estimate_m) || !std::isfinite(variance))
    return std::nullopt;
  // Not before the frames know r̄ at least twice as well as the prior.
  if (variance > 0.5 * prior_var_) return std::nullopt;
  const double moved_var = prior_var_ - variance;
  const double moved = estimate_m - prior_m_;
  const double d2 = moved * moved / (moved_var + scale_var_);
  if (!(d2 > chi2_)) return std::nullopt;
  SpacingMismatch m;
  m.profile_m = prior_m_;
  m.profile_sd_m = std::sqrt(prior_var_ + scale_var_);
  m.estimate_m = estimate_m;
  m.measured_m = prior_m_ + moved * prior_var_ / moved_var;
  m.measured_sd_m = std::sqrt(variance * prior_var_ / moved_var + scale_var_);
  m.chi2 = d2;
  current_ = m;
  return m;
}

std::string SpacingMismatch::Text() const {
  char b[256];
  std::snprintf(b, sizeof b,
                "row spacing measured %.3f m ± %.3f, the crop profile says %.3f m ± %.3f "
                "(d² %.1f): check the profile's row_spacing_m",
                measured_m, measured_sd_m, profile_m, profile_sd_m, chi2);
  return b;
}

}  // namespace plantscale::tracking
