#pragma once
// The station live over the gateway (`station --connect wss://…`): the
// gateway client (telemetry/gateway/client.h) hands each LCM message's
// bytes, as the vehicle published them, to the same Subscriber and run
// model as the live LCM source, so everything after decoding is the code
// path of `--lcm-url`. Commands are signed here as there and published
// through the gateway (operators only; a viewer's are refused here, and
// would be at the gateway). The HUD's status says the link: connected as
// whom, or down and when the next attempt is.

#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "telemetry/gateway/client.h"
#include "ui/station_sources.h"

namespace plantscale::ui {

class GatewaySource : public Source {
 public:
  // Starts connecting; throws telemetry::gateway::GatewayClientError (the CA file).
  GatewaySource(const telemetry::gateway::GatewayClientOptions& options,
                std::optional<telemetry::CommandKey> command_key)
      : command_key_(std::move(command_key)) {
    subscriber_.SetObserver([this](const std::string& ch, bool applied, const telemetry::TelemetrySnapshot& s) {
      std::lock_guard lock(mutex);
      model_.Observe(ch, applied, s);
    });
    client_ = std::make_unique<telemetry::gateway::GatewayClient>(
        options, [this](const std::string& channel, const void* data, size_t size, int64_t recv_utime) {
          if (Repeated(channel, data, size)) return;
          subscriber_.Feed(channel, data, size, recv_utime);
        });
  }
  ~GatewaySource() override { client_.reset(); }  // its thread feeds the subscriber: stopped first

  // Waits for the first connection (see GatewayClient::WaitFirstAttempt):
  // throws GatewayClientError when the token is refused or the certificate
  // is not trusted.
  void WaitFirstAttempt(double timeout_s) { client_->WaitFirstAttempt(timeout_s); }

  void Tick(double) override {
    const std::string text = telemetry::gateway::LinkText(client_->status());
    const auto state = client_->status().state;
    if (changes_.empty() || state != last_state_) {
      char stamp[32];
      std::snprintf(stamp, sizeof stamp, "%.3f", 1e-6 * static_cast<double>(telemetry::WallUtime()));
      changes_.push_back(std::string(stamp) + " " + text);
      last_state_ = state;
    }
  }
  const review::RunModel& model() const override { return model_; }
  int64_t now_utime() const override { return telemetry::WallUtime(); }
  std::string Status() const override {
    const telemetry::gateway::GatewayLinkStatus s = client_->status();
    std::string text = telemetry::gateway::LinkText(s);
    if (!s.last_status.empty()) text += "  gateway says: " + s.last_status;
    return text;
  }
  std::string SendCommand(int8_t command, int8_t mode) override {
    const plantscale_command_t c = NewStationCommand(command, mode, command_seq_, command_key_);
    const std::string what = CommandText(command, mode);
    const std::string result = client_->PublishCommand(c);
    if (result != "sent") return "command " + what + " " + result;
    return std::string(command_key_ ? "sent to the vehicle through the gateway: "
                                    : "sent unsigned (no --command-key) through the gateway: ") +
           what;
  }
  std::vector<std::string> LinkChanges() const override { return changes_; }
  int64_t LinkBytes() const override { return client_->status().bytes; }
  telemetry::gateway::GatewayLinkStatus link() const { return client_->status(); }

 private:
  // The gateway sends the latest message of each channel again on every
  // (re)subscription: the same bytes as the last received on that channel
  // are that message again, not a new one (every message has a seq).
  bool Repeated(const std::string& channel, const void* data, size_t size) {
    std::string& last = last_bytes_[channel];
    const std::string bytes(static_cast<const char*>(data), size);
    if (bytes == last) return true;
    last = bytes;
    return false;
  }

  int64_t command_seq_ = 0;
  std::optional<telemetry::CommandKey> command_key_;
  telemetry::Subscriber subscriber_;
  review::RunModel model_;
  std::map<std::string, std::string> last_bytes_;  // client thread only
  std::vector<std::string> changes_;               // UI thread (Tick) only
  telemetry::gateway::LinkState last_state_ = telemetry::gateway::LinkState::kConnecting;
  std::unique_ptr<telemetry::gateway::GatewayClient> client_;
};

}  // namespace plantscale::ui
