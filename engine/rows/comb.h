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

// Σ w_b e^{i(a0 + b·da)} over the weights w_b, and Σ w_b.
struct Phasor {
  double re = 0.0, im = 0.0, mass = 0.0;
};
// The phasor advances by a fixed rotation per weight (std::complex's
// product checks for NaN at every step), in eight interleaved chains
// (weights b … b + 7, each rotated by eight weights' angle) held as two
// four-lane vectors, so the steps do not wait on each other (one AVX2
// instruction each where the CPU has it, engine/common/vectorise.h). Every
// lane does what a scalar loop would: the sums are the same to the last
// bit on any vector width.
Phasor PhasorSum(std::span<const double> w, double a0, double da);
Phasor PhasorSum(std::span<const float> w, double a0, double da);

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
