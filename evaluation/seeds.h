#pragma once
// The one seed loop of the simulated evaluations (tracking, treatment,
// segmentation, motion, rows): a run of `seeds` seeds from the preset's
// seed is seed, seed + 1, …, seed + seeds − 1, each one simulator built
// from the preset's options with that seed. Every evaluation loops through
// ForEachSeed and names a run's seed with NthSeed, so their JSON's
// per-seed entries, a figure's seeds and a rerun of one seed agree.

#include <cstdint>
#include <functional>

#include "engine/sim/simulator.h"

namespace plantscale::app {

// The k-th seed (k from 0) of a run starting at `first`.
uint64_t NthSeed(uint64_t first, int k);

// Calls `run(k, options)` for k = 0 … seeds − 1 in order, `options` being
// `preset` with its seed set to NthSeed(preset.seed, k); the call may change
// its copy (a shorter field, another view) before building the simulator.
void ForEachSeed(const sim::SimulatorOptions& preset, int seeds,
                 const std::function<void(int k, sim::SimulatorOptions& options)>& run);

}  // namespace plantscale::app
