#include "app/commands.h"

#include "app/archive_commands.h"
#include "app/command_auth_commands.h"
#include "app/demo_commands.h"
#include "app/export_commands.h"
#include "app/figures_commands.h"
#include "app/gateway_commands.h"
#include "app/learning_commands.h"
#include "app/log_eval_commands.h"
#include "app/motion_commands.h"
#include "app/rows_commands.h"
#include "app/segment_commands.h"
#include "app/simulate_commands.h"
#include "app/spraybar_commands.h"
#include "app/telemetry_commands.h"
#include "app/tracking_commands.h"
#include "app/treatment_commands.h"
#include "app/ui_commands.h"

namespace plantscale::app {

CommandLine::CommandLine(CLI::App& cli) : registry_(cli) {
  AddSimulateCommands(registry_);
  AddSegmentCommands(registry_);
  AddTelemetryCommands(registry_);
  AddExportCommands(registry_);
  AddArchiveCommands(registry_);
  AddTrackingCommands(registry_);
  AddTreatmentCommands(registry_);
  AddLogEvalCommands(registry_);
  AddMotionCommands(registry_);
  AddRowsCommands(registry_);
  AddUiCommands(registry_);
  AddDemoCommands(registry_);
  AddSprayBarCommands(registry_);
  AddCommandAuthCommands(registry_);
  AddLearningCommands(registry_);
  AddGatewayCommands(registry_);
  AddFiguresCommands(registry_);
}

}  // namespace plantscale::app
