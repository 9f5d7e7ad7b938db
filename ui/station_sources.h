#pragma once
// Where the station's run model comes from: a log played on a timeline
// (pause, speed, seek), or live LCM with the subscriber on its own thread.
// The mutex guards the model between that thread and the UI thread.

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>
#include <plantscale_lcmtypes/plantscale_command_t.hpp>

#include "review/log_timeline.h"
#include "telemetry/channels.h"
#include "telemetry/codec.h"
#include "telemetry/command_auth.h"
#include "telemetry/transport.h"

namespace plantscale::ui {

// Where the model comes from: a log with a timeline, or live LCM.
class Source {
 public:
  virtual ~Source() = default;
  virtual void Tick(double wall_s) = 0;
  virtual const review::RunModel& model() const = 0;
  virtual int64_t now_utime() const = 0;
  virtual double fraction() const { return -1.0; }  // timeline position, < 0 live
  virtual double position_s() const { return -1.0; }  // log clock from its start, < 0 live
  virtual double duration_s() const { return -1.0; }  // of the log, < 0 live
  virtual void Seek(double, bool) {}
  virtual void TogglePause() {}
  virtual void ScaleSpeed(double) {}
  virtual std::string Status() const = 0;
  virtual std::string LogError() const { return ""; }  // the log could not be read to its end
  virtual bool review() const { return false; }  // a finished run: nothing plays
  // Sends a station command to the vehicle (plantscale_command_t COMMAND_*,
  // MODE_* with COMMAND_SET_MODE); returns what happened, for the HUD.
  virtual std::string SendCommand(int8_t /*command*/, int8_t /*mode*/) {
    return "vehicle commands need a live station (--lcm-url or --connect), not a log";
  }
  // Over the gateway: each change of the link, "UNIX_SECONDS TEXT".
  virtual std::vector<std::string> LinkChanges() const { return {}; }
  // Over the gateway: the LCM message bytes received so far; else -1.
  virtual int64_t LinkBytes() const { return -1; }
  std::mutex mutex;  // held while the model is read or changed
};

class LogSource : public Source {
 public:
  LogSource(const std::filesystem::path& log, double speed) : timeline_(review::LogTimeline::Load(log)) {
    timeline_.SetSpeed(speed);
    timeline_.Seek(0.0);
  }
  void Tick(double wall_s) override { timeline_.Advance(wall_s); }
  const review::RunModel& model() const override { return timeline_.model(); }
  int64_t now_utime() const override { return timeline_.now_utime(); }
  double fraction() const override {
    return timeline_.duration_s() > 0 ? timeline_.position_s() / timeline_.duration_s() : 0.0;
  }
  double position_s() const override { return timeline_.position_s(); }
  double duration_s() const override { return timeline_.duration_s(); }
  void Seek(double value, bool relative) override {
    timeline_.Seek(relative ? timeline_.position_s() + value : value * timeline_.duration_s());
  }
  void TogglePause() override { timeline_.SetPaused(!timeline_.paused()); }
  std::string LogError() const override { return timeline_.error(); }
  void ScaleSpeed(double f) override { timeline_.SetSpeed(std::clamp(timeline_.speed() * f, 0.125, 64.0)); }
  std::string Status() const override {
    std::ostringstream out;
    out.precision(1);
    out << std::fixed << (timeline_.paused() ? "PAUSED " : "") << "log " << timeline_.position_s() << "/"
        << timeline_.duration_s() << " s x" << timeline_.speed();
    if (!timeline_.error().empty()) out << "  LOG CUT: " << timeline_.error();
    if (timeline_.empty()) out << "  (log has no events)";
    return out.str();
  }

 private:
  review::LogTimeline timeline_;
};

// A finished run, whole (a log's, LoadReviewRun, or an exported map's
// plants, read in app/). Nothing plays; the station's timeline is the bed.
class ReviewSource : public Source {
 public:
  ReviewSource(std::shared_ptr<const review::RunModel> model, std::string what, std::string error = "")
      : what_(std::move(what)), model_(std::move(model)), error_(std::move(error)) {}
  void Tick(double) override {}
  const review::RunModel& model() const override { return *model_; }
  int64_t now_utime() const override { return model_->last_message_utime(); }
  bool review() const override { return true; }
  std::string LogError() const override { return error_; }
  std::string Status() const override {
    std::string s = "review " + what_ + ": " + std::to_string(model_->plants().size()) + " plants";
    if (!error_.empty()) s += "  LOG CUT: " + error_;
    return s;
  }

 private:
  std::string what_;
  std::shared_ptr<const review::RunModel> model_;
  std::string error_;
};

// A station command (plantscale_command_t COMMAND_*, MODE_* with
// COMMAND_SET_MODE) stamped now, from station@HOST, signed with `key` when
// given. Its seq is the wall clock's microseconds (or one more than
// `last_seq`, which it updates): seqs keep increasing across station
// restarts, which the vehicle's replay check needs.
inline plantscale_command_t NewStationCommand(int8_t command, int8_t mode, int64_t& last_seq,
                                              const std::optional<telemetry::CommandKey>& key) {
  plantscale_command_t c{};
  c.utime = telemetry::WallUtime();
  last_seq = std::max(last_seq + 1, c.utime);
  c.seq = last_seq;
  c.command = command;
  c.mode = mode;
  char host[256] = "station";
  gethostname(host, sizeof host - 1);
  c.origin = std::string("station@") + host;
  if (key) telemetry::Sign(c, *key);
  return c;
}

// A command in words ("spray the crop").
inline std::string CommandText(int8_t command, int8_t mode) {
  if (command == plantscale_command_t::COMMAND_START) return "start";
  if (command == plantscale_command_t::COMMAND_PAUSE) return "pause";
  if (mode == plantscale_command_t::MODE_SPRAY_CROP) return "spray the crop";
  if (mode == plantscale_command_t::MODE_SPRAY_WEED) return "spray the weeds";
  return "spraying off";
}

// Commands are signed with `command_key` (telemetry/command_auth.h); without
// one they go unsigned, and a vehicle obeys them only with
// --accept-unsigned-commands.
class LiveSource : public Source {
 public:
  explicit LiveSource(const std::string& url, std::optional<telemetry::CommandKey> command_key = {})
      : command_key_(std::move(command_key)),
        transport_(url.empty() ? telemetry::LcmTransportOptions{}.url : url) {
    subscriber_.SetObserver([this](const std::string& ch, bool applied, const telemetry::TelemetrySnapshot& s) {
      std::lock_guard lock(mutex);
      model_.Observe(ch, applied, s);
    });
    subscriber_.Attach(transport_);
    thread_ = std::thread([this] {
      while (!stop_) transport_.Handle(50);
    });
  }
  ~LiveSource() override {
    stop_ = true;
    thread_.join();
  }
  void Tick(double) override {}
  const review::RunModel& model() const override { return model_; }
  int64_t now_utime() const override { return telemetry::WallUtime(); }
  std::string Status() const override { return "live " + transport_.url(); }
  std::string SendCommand(int8_t command, int8_t mode) override {
    const plantscale_command_t c = NewStationCommand(command, mode, command_seq_, command_key_);
    const telemetry::Bytes bytes = telemetry::Encode(c);
    try {
      transport_.Publish(telemetry::channels::kCommand, bytes.data(), bytes.size());
    } catch (const telemetry::TransportError& e) {
      return std::string("command not sent: ") + e.what();
    }
    return std::string(command_key_ ? "sent to the vehicle: " : "sent unsigned (no --command-key): ") +
           CommandText(command, mode);
  }
  const telemetry::Subscriber& subscriber() const { return subscriber_; }

 private:
  int64_t command_seq_ = 0;
  std::optional<telemetry::CommandKey> command_key_;
  telemetry::LcmTransport transport_;
  telemetry::Subscriber subscriber_;
  review::RunModel model_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace plantscale::ui
