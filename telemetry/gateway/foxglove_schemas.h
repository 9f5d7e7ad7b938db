#pragma once
// JSON Schemas of what the gateway serves (docs/remote.md): Foxglove's
// well-known message schemas where one fits, so that Foxglove or Lichtblick
// draws a channel with no plugin (the schema name selects the panel; the
// JSON follows the field names of foxglove/schemas), and plantscale's own
// flat schemas, whose numbers a Plot panel plots, for the rest.
// Each schema is a JSON Schema (draft 2020-12 subset) as a string, as the
// advertise message carries it.

#include <nlohmann/json.hpp>
#include <string>

namespace plantscale::telemetry::gateway::schemas {

// Foxglove's well-known types (the parts plantscale fills).
nlohmann::json CompressedImage();  // foxglove.CompressedImage
nlohmann::json SceneUpdate();      // foxglove.SceneUpdate (spheres, lines, texts)
nlohmann::json Grid();             // foxglove.Grid
nlohmann::json Log();              // foxglove.Log

// plantscale's own: flat objects of plottable numbers.
nlohmann::json GridState();  // plantscale.GridState
nlohmann::json Health();     // plantscale.Health
nlohmann::json Nozzles();    // plantscale.Nozzles
nlohmann::json Odometry();   // plantscale.Odometry
nlohmann::json Pose();       // plantscale.Pose
nlohmann::json Command();    // plantscale.Command (also what an operator publishes)

}  // namespace plantscale::telemetry::gateway::schemas
