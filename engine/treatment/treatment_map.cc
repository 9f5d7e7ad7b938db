#include "engine/treatment/treatment_map.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace plantscale::treatment {

namespace {

// Rows the map keeps at once (≈ 1.3 km at 13 mm): a map whose rows behind
// the bar are never forgotten stops counting there.
constexpr int kMaxWindowRows = 100000;
// Row index of the last cell of a bed (≈ 3 600 km at 13 mm).
constexpr int kMaxRows = 1 << 28;

// Where the convex quad crosses the line at `at` along axis `k` (0: x =
// at, 1: y = at): the range [lo, hi] of the other coordinate; lo > hi when
// it does not reach the line.
void SpanAt(const Quad& q, int k, double at, double& lo, double& hi) {
  const int o = 1 - k;
  lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (size_t i = 0; i < 4; ++i) {
    const Eigen::Vector2d& a = q[i];
    const Eigen::Vector2d& b = q[(i + 1) % 4];
    if ((a[k] - at) * (b[k] - at) > 0.0) continue;  // the edge does not reach the line
    if (a[k] == b[k]) {
      lo = std::min({lo, a[o], b[o]}), hi = std::max({hi, a[o], b[o]});
    } else {
      const double v = a[o] + (at - a[k]) / (b[k] - a[k]) * (b[o] - a[o]);
      lo = std::min(lo, v), hi = std::max(hi, v);
    }
  }
}

}  // namespace

OptionErrors TreatmentMapOptions::Validate() const {
  OptionErrors e;
  RequireInRange(e, "cell_m", cell_m, 0.001, 0.5);
  RequireInRange(e, "width_m", width_m, 0.1, 50.0);
  if (!std::isfinite(start_y_m)) e.push_back({"start_y_m", "must be finite"});
  if (majority_threshold < 1) e.push_back({"majority_threshold", "must be >= 1"});
  if (weed_majority_threshold < 0) e.push_back({"weed_majority_threshold", "must be >= 0 (0: majority_threshold)"});
  return e;
}

TreatmentMap::TreatmentMap(const TreatmentMapOptions& options) : options_(options) {
  ThrowIfInvalid("treatment map", options_.Validate());
  columns_ = static_cast<int>(std::ceil(options_.width_m / options_.cell_m));
}

void TreatmentMap::GrowTo(int row) {
  if (row >= rows()) {
    counts_.resize(static_cast<size_t>(row + 1 - first_row_) * columns_);
    flags_.resize(counts_.size());
  }
}

int TreatmentMap::LastRow() const { return std::min(kMaxRows, first_row_ + kMaxWindowRows) - 1; }

void TreatmentMap::Clear() {
  counts_.clear();
  flags_.clear();
  first_row_ = 0;
}

void TreatmentMap::ForgetBefore(int row) {
  if (row <= first_row_) return;
  const int drop = std::min(row, rows()) - first_row_;
  const auto n = static_cast<std::ptrdiff_t>(drop) * columns_;
  counts_.erase(counts_.begin(), counts_.begin() + n);
  flags_.erase(flags_.begin(), flags_.begin() + n);
  first_row_ = row;
}

bool TreatmentMap::CellOf(const Eigen::Vector2d& b, int& column, int& row) const {
  const double c = std::floor((b.x() - origin_x_m()) / options_.cell_m);
  const double r = std::floor((b.y() - options_.start_y_m) / options_.cell_m);
  if (!(c >= 0 && c < columns_ && r >= 0 && r < kMaxRows)) return false;
  column = static_cast<int>(c);
  row = static_cast<int>(r);
  return true;
}

Eigen::Vector2d TreatmentMap::CellCentre(int column, int row) const {
  return {origin_x_m() + (column + 0.5) * options_.cell_m,
          options_.start_y_m + (row + 0.5) * options_.cell_m};
}

CellCounts TreatmentMap::Counts(int column, int row) const {
  if (column < 0 || column >= columns_ || row < first_row_ || row >= rows()) return {};
  return counts_[Index(column, row)];
}

CellClass TreatmentMap::ClassOf(int column, int row) const {
  const CellCounts c = Counts(column, row);
  if (c.crop >= c.weed) {
    return c.crop >= options_.majority_threshold && c.crop >= c.weed + c.doubt ? CellClass::kCrop
                                                                            : CellClass::kSoil;
  }
  const int weed_threshold = options_.weed_majority_threshold > 0 ? options_.weed_majority_threshold
                                                                  : options_.majority_threshold;
  return c.weed >= weed_threshold ? CellClass::kWeed : CellClass::kSoil;
}

CellClass TreatmentMap::ClassAt(const Eigen::Vector2d& b) const {
  int column = 0, row = 0;
  return CellOf(b, column, row) ? ClassOf(column, row) : CellClass::kSoil;
}

template <typename F>
int TreatmentMap::ForCellsIn(const Quad& q, F&& f) {
  double x0 = q[0].x(), x1 = x0, y0 = q[0].y(), y1 = y0;
  for (const Eigen::Vector2d& p : q) {
    if (!p.allFinite()) return 0;
    x0 = std::min(x0, p.x()), x1 = std::max(x1, p.x());
    y0 = std::min(y0, p.y()), y1 = std::max(y1, p.y());
  }
  const double s = options_.cell_m;
  const int c0 = std::max(0, static_cast<int>(std::floor((x0 - origin_x_m()) / s)));
  const int c1 = std::min(columns_ - 1, static_cast<int>(std::floor((x1 - origin_x_m()) / s)));
  const double last = std::min<double>(LastRow(), std::floor((y1 - options_.start_y_m) / s));
  const double first = std::max<double>(first_row_, std::floor((y0 - options_.start_y_m) / s));
  if (c0 > c1 || !(first <= last)) return 0;
  const int r0 = static_cast<int>(first), r1 = static_cast<int>(last);
  GrowTo(r1);
  // Row by row, the quad's span at the row's centre line: centres clearly
  // inside it are inside the quad; the few within kEdge of its ends are
  // tested as points (InsideQuad), so the cells are exactly InsideQuad's.
  constexpr double kEdge = 1e-9;
  int cells = 0;
  for (int r = r0; r <= r1; ++r) {
    const double y = options_.start_y_m + (r + 0.5) * s;
    double lo = 0.0, hi = 0.0;
    SpanAt(q, 1, y, lo, hi);
    if (!(lo <= hi)) continue;
    const int ca = std::max(c0, static_cast<int>(std::ceil((lo - kEdge - origin_x_m()) / s - 0.5)));
    const int cb = std::min(c1, static_cast<int>(std::floor((hi + kEdge - origin_x_m()) / s - 0.5)));
    for (int c = ca; c <= cb; ++c) {
      const double x = origin_x_m() + (c + 0.5) * s;
      if (!(x > lo + kEdge && x < hi - kEdge) && !InsideQuad(q, {x, y})) continue;
      f(Index(c, r));
      ++cells;
    }
  }
  return cells;
}

void TreatmentMap::Vote(uint16_t& n, int votes) {
  n = static_cast<uint16_t>(std::clamp(n + votes, 0, int{std::numeric_limits<uint16_t>::max()}));
}

int TreatmentMap::AddFootprint(const Quad& q, bool crop) {
  return ForCellsIn(q, [&](size_t i) { Vote(i, 1, crop); });
}

int TreatmentMap::AddDoubt(const Quad& q) {
  return ForCellsIn(q, [&](size_t i) { Vote(counts_[i].doubt, 1); });
}

void TreatmentMap::AppendSpans(const Quad& q, double along_m,
                               std::vector<ColumnSpan>& out) const {
  double x0 = q[0].x(), x1 = x0;
  for (const Eigen::Vector2d& p : q) {
    if (!p.allFinite()) return;
    x0 = std::min(x0, p.x()), x1 = std::max(x1, p.x());
  }
  const double s = options_.cell_m;
  const int c0 = std::max(0, static_cast<int>(std::floor((x0 - origin_x_m()) / s)));
  const int c1 = std::min(columns_ - 1, static_cast<int>(std::floor((x1 - origin_x_m()) / s)));
  for (int c = c0; c <= c1; ++c) {
    const double x = origin_x_m() + (c + 0.5) * s;
    double lo = 0.0, hi = 0.0;
    SpanAt(q, 0, x, lo, hi);
    if (lo <= hi) out.push_back({c, lo - along_m, hi - along_m});
  }
}

int TreatmentMap::AddSpans(std::span<const ColumnSpan> spans, double along_m, int votes,
                           bool crop) {
  const double s = options_.cell_m;
  int cells = 0;
  for (const ColumnSpan& span : spans) {
    // Rows whose centre start + (r + 0.5) s lies in [y0, y1].
    const double first = std::ceil((span.y0_m + along_m - options_.start_y_m) / s - 0.5);
    const double last = std::floor((span.y1_m + along_m - options_.start_y_m) / s - 0.5);
    if (!(first <= last) || last < first_row_ || first > LastRow()) continue;
    const int r0 = static_cast<int>(std::max<double>(first, first_row_));
    const int r1 = static_cast<int>(std::min<double>(last, LastRow()));
    GrowTo(r1);
    for (int r = r0; r <= r1; ++r) Vote(Index(span.column, r), votes, crop);
    cells += r1 - r0 + 1;
  }
  return cells;
}

void TreatmentMap::MarkObserved(const Quad& q) {
  ForCellsIn(q, [&](size_t i) { flags_[i] |= kObservedFlag; });
}

TreatmentMap::CellRange TreatmentMap::RangeOf(double x0, double x1, double y0, double y1) const {
  const double s = options_.cell_m;
  // Cells whose centre lies in the rectangle: centre = origin + (i + ½) s.
  CellRange k{static_cast<int>(std::ceil((x0 - origin_x_m()) / s - 0.5)),
              static_cast<int>(std::floor((x1 - origin_x_m()) / s - 0.5)),
              static_cast<int>(std::ceil((y0 - options_.start_y_m) / s - 0.5)),
              static_cast<int>(std::floor((y1 - options_.start_y_m) / s - 0.5))};
  int column = 0, row = 0;
  if ((k.c0 > k.c1 || k.r0 > k.r1) && CellOf({0.5 * (x0 + x1), 0.5 * (y0 + y1)}, column, row)) {
    if (k.c0 > k.c1) k.c0 = k.c1 = column;
    if (k.r0 > k.r1) k.r0 = k.r1 = row;
  }
  k.c0 = std::max(k.c0, 0);
  k.c1 = std::min(k.c1, columns_ - 1);
  k.r0 = std::max(k.r0, first_row_);
  k.r1 = std::min(k.r1, LastRow());
  return k;
}

bool TreatmentMap::AnyIn(double x0, double x1, double y0, double y1, CellClass cls) const {
  const CellRange k = RangeOf(x0, x1, y0, y1);
  for (int r = k.r0; r <= std::min(k.r1, rows() - 1); ++r) {
    for (int c = k.c0; c <= k.c1; ++c) {
      if (ClassOf(c, r) == cls) return true;
    }
  }
  return false;
}

void TreatmentMap::MarkTreated(double x0, double x1, double y0, double y1) {
  const CellRange k = RangeOf(x0, x1, y0, y1);
  if (k.c0 > k.c1 || k.r0 > k.r1) return;
  GrowTo(k.r1);
  for (int r = k.r0; r <= k.r1; ++r) {
    for (int c = k.c0; c <= k.c1; ++c) flags_[Index(c, r)] |= kTreatedFlag;
  }
}

uint8_t TreatmentMap::Flags(int column, int row) const {
  if (column < 0 || column >= columns_ || row < first_row_ || row >= rows()) return 0;
  return flags_[Index(column, row)];
}

}  // namespace plantscale::treatment
