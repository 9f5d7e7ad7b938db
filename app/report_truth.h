#pragma once
// The simulator's truth over a report's stand (`plantscale report`, the
// truth column of index.html and summary.json): the simulated field rebuilt
// from the log's run_config event (app/config/run_config.h), registered on
// the crop records (the shift in rows and metres along under which most
// crop records have a true crop within 6 cm; the pattern of missing plants
// and the spacing drift make it unique), and its plants counted in the same
// rows and along the same stand (review/agronomy.h definitions).

#include <optional>
#include <string>

#include "review/agronomy.h"

namespace plantscale::app {

// `config_dir_option`: --config-dir (empty: the run's own config folder when
// it exists, else the default). Throws ConfigError (a bad run_config) and
// what building the simulator throws.
std::optional<review::AgronomyTruth> SimulatorTruth(const std::string& run_config, const review::StandWindow& stand,
                                                    const std::string& config_dir_option);

}  // namespace plantscale::app
