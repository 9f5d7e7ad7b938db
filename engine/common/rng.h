#pragma once
// A seeded random source whose output is identical on every platform and
// standard library (std::normal_distribution is implementation-defined), so
// that "same seed, same bytes" holds for the simulator.

#include <cstdint>

namespace plantscale {

class Rng {
 public:
  explicit Rng(uint64_t seed);

  uint64_t NextU64();  // xoshiro256** step
  double Uniform();    // [0, 1)
  double Uniform(double low, double high);
  double Normal();  // standard normal (Marsaglia polar method)
  double Normal(double mean, double sd) { return mean + sd * Normal(); }
  double LogNormal(double median, double log_sd);  // median * exp(log_sd * N(0,1))
  bool Bernoulli(double p) { return Uniform() < p; }
  int Poisson(double mean);  // Knuth for small means, normal approx. above 50
  // An independent stream derived from this seed and a label (splitmix64).
  static Rng Derived(uint64_t seed, uint64_t stream);

 private:
  uint64_t state_[4];
  bool has_spare_ = false;
  double spare_ = 0.0;
};

}  // namespace plantscale
