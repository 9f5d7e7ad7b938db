#include "evaluation/seeds.h"

namespace plantscale::app {

uint64_t NthSeed(uint64_t first, int k) { return first + static_cast<uint64_t>(k); }

void ForEachSeed(const sim::SimulatorOptions& preset, int seeds,
                 const std::function<void(int k, sim::SimulatorOptions& options)>& run) {
  for (int k = 0; k < seeds; ++k) {
    sim::SimulatorOptions options = preset;
    options.seed = NthSeed(preset.seed, k);
    run(k, options);
  }
}

}  // namespace plantscale::app
