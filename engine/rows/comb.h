#pragma once
// The row comb: crop rows are a comb of teeth n·period + phase along one
// coordinate across the rows (the lateral ground coordinate on the
// calibrated ground plane, or the bottom-row crossing s in the image). One
// piece of code scores plant matter against the comb for both the image
// detector (row_detector.h) and the tracker's ground-plane initialiser
// (engine/tracking/initialiser.h, whose Hough over (t_x, Ψ) votes with
// VoteComb).

#include <span>
#include <vector>

namespace plantscale::rows {

struct CombFit {
  double period = 0.0;
  double phase = 0.0;      // a tooth sits at phase + n·period, phase in [0, period)
  double coherence = 0.0;  // |Σ w e^{−2πi x/period}| / Σ w: 1 when every weight sits on a tooth
};

// Phase coherence of a histogram (bin b centred at x0 + b·bin_width) with the
// comb of one period.
CombFit CombAt(std::span<const double> histogram, double x0, double bin_width, double period);

// The periods in [min_period, max_period] (geometric steps of relative size
// `step`) at which the coherence has a local maximum, best first, at most
// `max_fits`.
std::vector<CombFit> BestCombs(std::span<const double> histogram, double x0, double bin_width,
                               double min_period, double max_period, double step, int max_fits);

// Triangular votes of a weight w for the finite comb of teeth
// n = −teeth..teeth: tooth n of the comb through `position` lies at
// position − n·period; each vote spreads over ± spread bins of the
// accumulator row `line` (bin k at (k − half)·bin_width).
void VoteComb(std::span<double> line, int half, double bin_width, double position, double period,
              int teeth, int spread, double w);

}  // namespace plantscale::rows
