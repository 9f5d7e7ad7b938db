// linkem: a slow, lossy IP link between two network namespaces, emulated
// in user space (test support only; not part of plantscale).
//
// Issue 58 asks for the gateway measured over "two network namespaces joined
// by a veth pair with tc netem at 1 Mbit/s, 150 ms delay, 2 % loss". Kernels
// without the netem qdisc (this project's CI and development machines) still
// have TUN, and TUN works in an unprivileged user namespace. So:
//
//   unshare -rn linkem --rate 1000000 --delay 0.150 --loss 0.02 --seed 7
//       --a 'CMD run in namespace A' --b 'CMD run in namespace B' --stats stats.json
//   (one command line)
//
//  1. opens a TUN device `lkA` in the current network namespace (A), keeps
//     /proc/self/ns/net open, then unshare(CLONE_NEWNET) makes namespace B
//     and a TUN device `lkB` there (a TUN fd stays bound to the namespace it
//     was made in);
//  2. addresses them point to point, 10.77.0.1 (A) and 10.77.0.2 (B)
//     (--net 10.77.0 to change the /24), brings up lo in both and routes
//     multicast (224.0.0.0/4) on lo in both, so LCM stays in its namespace;
//  3. runs each command with /bin/sh -c in its namespace (setns) and moves
//     the IP packets between the two TUN fds until both commands exited.
//
// Each direction is its own netem-like queue: a packet arriving is lost at
// random (--loss, seeded), else tail-dropped when --limit packets are held
// already (like netem's limit, default 1000), else serialized at --rate
// bit/s behind the packets before it and delivered --delay seconds after
// its last bit left. A cut (--cut-at S --cut-for S after the commands
// start, or SIGUSR1 ... SIGUSR2) drops every packet arriving or due during
// it, as a pulled cable does: no FIN, no RST.
//
// Prints "linkem: ..." lines on stderr (the addresses, each cut's start and
// end as UNIX seconds) and, at the end, per direction counters as JSON on
// stderr and in --stats FILE. Exit status: 0 when both commands exited 0,
// 1 when either did not, 2 for bad arguments or a set-up failure (no TUN,
// no namespace: the caller's test skips on that, see tests/gateway/link.sh).

#include <fcntl.h>
#include <linux/if.h>
#include <linux/if_tun.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <sys/ioctl.h>
#include <sys/signalfd.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace {

[[noreturn]] void Die(const std::string& what) {
  std::fprintf(stderr, "linkem: error: %s\n", what.c_str());
  std::exit(2);
}

[[noreturn]] void DieErrno(const std::string& what) { Die(what + ": " + std::strerror(errno)); }

double Monotonic() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double Unix() {
  timespec t{};
  clock_gettime(CLOCK_REALTIME, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

struct Options {
  double rate_bps = 1e6;
  double delay_s = 0.150;
  double loss = 0.02;
  uint64_t seed = 1;
  size_t limit = 1000;
  double cut_at_s = -1.0;
  double cut_for_s = 0.0;
  std::string net = "10.77.0";
  std::string cmd_a, cmd_b;
  std::string stats;
};

double ParseNumber(const std::string& option, const std::string& text, double lo, double hi) {
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || errno != 0 || !(v >= lo && v <= hi)) {
    std::ostringstream s;
    s << option << " '" << text << "': expected a number in [" << lo << ", " << hi << "]";
    Die(s.str());
  }
  return v;
}

Options Parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (i + 1 >= argc) Die(arg + ": expected a value after it (see the header of tests/gateway/linkem.cc)");
    const std::string v = argv[++i];
    if (arg == "--rate") {
      o.rate_bps = ParseNumber(arg, v, 1e3, 1e11);
    } else if (arg == "--delay") {
      o.delay_s = ParseNumber(arg, v, 0.0, 60.0);
    } else if (arg == "--loss") {
      o.loss = ParseNumber(arg, v, 0.0, 1.0);
    } else if (arg == "--seed") {
      o.seed = static_cast<uint64_t>(ParseNumber(arg, v, 0, 4e9));
    } else if (arg == "--limit") {
      o.limit = static_cast<size_t>(ParseNumber(arg, v, 1, 1e7));
    } else if (arg == "--cut-at") {
      o.cut_at_s = ParseNumber(arg, v, 0.0, 1e6);
    } else if (arg == "--cut-for") {
      o.cut_for_s = ParseNumber(arg, v, 0.0, 1e6);
    } else if (arg == "--net") {
      o.net = v;
    } else if (arg == "--a") {
      o.cmd_a = v;
    } else if (arg == "--b") {
      o.cmd_b = v;
    } else if (arg == "--stats") {
      o.stats = v;
    } else {
      Die("unknown option " + arg);
    }
  }
  if (o.cmd_a.empty() || o.cmd_b.empty()) Die("--a CMD and --b CMD are both required");
  if ((o.cut_at_s >= 0) != (o.cut_for_s > 0)) Die("--cut-at and --cut-for go together");
  return o;
}

int OpenTun(const char* name) {
  const int fd = open("/dev/net/tun", O_RDWR | O_CLOEXEC);
  if (fd < 0) DieErrno("/dev/net/tun");
  ifreq ifr{};
  ifr.ifr_flags = IFF_TUN | IFF_NO_PI;
  std::strncpy(ifr.ifr_name, name, IFNAMSIZ - 1);
  if (ioctl(fd, TUNSETIFF, &ifr) < 0) DieErrno(std::string("TUNSETIFF ") + name);
  const int flags = fcntl(fd, F_GETFL);
  if (flags < 0 || fcntl(fd, F_SETFL, flags | O_NONBLOCK) < 0) DieErrno("O_NONBLOCK on the TUN device");
  return fd;
}

// Runs a command (argv, no shell) in the current namespace and waits for it.
void Run(const std::vector<std::string>& args) {
  const pid_t pid = fork();
  if (pid < 0) DieErrno("fork");
  if (pid == 0) {
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execvp(argv[0], argv.data());
    std::fprintf(stderr, "linkem: error: %s: %s\n", argv[0], std::strerror(errno));
    _exit(127);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::string line;
    for (const std::string& a : args) line += (line.empty() ? "" : " ") + a;
    Die("'" + line + "' failed");
  }
}

void Configure(const std::string& dev, const std::string& local, const std::string& peer) {
  Run({"ip", "link", "set", "lo", "up"});
  Run({"ip", "route", "add", "224.0.0.0/4", "dev", "lo"});
  Run({"ip", "addr", "add", local, "peer", peer, "dev", dev});
  Run({"ip", "link", "set", dev, "up"});
}

void EnterNamespace(int ns_fd) {
  if (setns(ns_fd, CLONE_NEWNET) < 0) DieErrno("setns");
}

pid_t Spawn(const std::string& cmd, int ns_fd, const sigset_t& original_mask) {
  const pid_t pid = fork();
  if (pid < 0) DieErrno("fork");
  if (pid == 0) {
    if (setns(ns_fd, CLONE_NEWNET) < 0) {
      std::fprintf(stderr, "linkem: error: setns: %s\n", std::strerror(errno));
      _exit(127);
    }
    sigprocmask(SIG_SETMASK, &original_mask, nullptr);
    execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    std::fprintf(stderr, "linkem: error: /bin/sh: %s\n", std::strerror(errno));
    _exit(127);
  }
  return pid;
}

struct Packet {
  std::vector<uint8_t> data;
  double due = 0.0;  // monotonic seconds: delivered then
};

struct Counters {
  int64_t packets_in = 0, bytes_in = 0;
  int64_t passed = 0, bytes_passed = 0;
  int64_t lost = 0;          // random loss
  int64_t tail_dropped = 0;  // over the limit
  int64_t cut = 0;           // dropped by a cut
  int64_t write_failed = 0;  // the far TUN refused it (not up, full)
  size_t max_held = 0;
  double max_delay_s = 0.0;  // arrival to delivery, the most any packet waited
};

// One direction of the link.
class Direction {
 public:
  Direction(const Options& o, std::mt19937_64& rng) : o_(o), rng_(rng) {}

  void Arrive(std::vector<uint8_t> data, double now, bool cut) {
    ++c_.packets_in;
    c_.bytes_in += static_cast<int64_t>(data.size());
    if (cut) {
      ++c_.cut;
      return;
    }
    if (o_.loss > 0 && std::uniform_real_distribution<double>(0.0, 1.0)(rng_) < o_.loss) {
      ++c_.lost;
      return;
    }
    if (held_.size() >= o_.limit) {
      ++c_.tail_dropped;
      return;
    }
    // Serialized behind the packets before it, then the one-way delay.
    const double start = std::max(now, link_free_);
    link_free_ = start + 8.0 * static_cast<double>(data.size()) / o_.rate_bps;
    Packet p;
    p.data = std::move(data);
    p.due = link_free_ + o_.delay_s;
    c_.max_delay_s = std::max(c_.max_delay_s, p.due - now);
    held_.push_back(std::move(p));
    c_.max_held = std::max(c_.max_held, held_.size());
  }

  // Delivers (or drops, during a cut) what is due by `now` to `fd`.
  void Deliver(int fd, double now, bool cut) {
    while (!held_.empty() && held_.front().due <= now) {
      const Packet& p = held_.front();
      if (cut) {
        ++c_.cut;
      } else if (write(fd, p.data.data(), p.data.size()) == static_cast<ssize_t>(p.data.size())) {
        ++c_.passed;
        c_.bytes_passed += static_cast<int64_t>(p.data.size());
      } else {
        ++c_.write_failed;
      }
      held_.pop_front();
    }
  }

  double next_due() const { return held_.empty() ? -1.0 : held_.front().due; }
  const Counters& counters() const { return c_; }

 private:
  const Options& o_;
  std::mt19937_64& rng_;
  std::deque<Packet> held_;  // due times increase: one FIFO per direction
  double link_free_ = 0.0;
  Counters c_;
};

std::string Json(const Counters& c, double seconds) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(3);
  s << "{\"packets_in\": " << c.packets_in << ", \"bytes_in\": " << c.bytes_in << ", \"passed\": " << c.passed
    << ", \"bytes_passed\": " << c.bytes_passed << ", \"lost\": " << c.lost
    << ", \"tail_dropped\": " << c.tail_dropped << ", \"cut\": " << c.cut
    << ", \"write_failed\": " << c.write_failed << ", \"max_held\": " << c.max_held
    << ", \"max_delay_s\": " << c.max_delay_s
    << ", \"bytes_per_s\": " << (seconds > 0 ? static_cast<double>(c.bytes_passed) / seconds : 0.0) << "}";
  return s.str();
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = Parse(argc, argv);
  const std::string ip_a = o.net + ".1", ip_b = o.net + ".2";

  const int tun_a = OpenTun("lkA");
  const int ns_a = open("/proc/self/ns/net", O_RDONLY | O_CLOEXEC);
  if (ns_a < 0) DieErrno("/proc/self/ns/net");
  if (unshare(CLONE_NEWNET) < 0) DieErrno("unshare(CLONE_NEWNET) (run linkem inside unshare -rn)");
  const int ns_b = open("/proc/self/ns/net", O_RDONLY | O_CLOEXEC);
  if (ns_b < 0) DieErrno("/proc/self/ns/net");
  const int tun_b = OpenTun("lkB");
  Configure("lkB", ip_b, ip_a);
  EnterNamespace(ns_a);
  Configure("lkA", ip_a, ip_b);
  std::fprintf(stderr, "linkem: A %s (lkA) <-> B %s (lkB): %.0f bit/s, %.3f s delay, %.4f loss, limit %zu packets, seed %llu each way\n",
               ip_a.c_str(), ip_b.c_str(), o.rate_bps, o.delay_s, o.loss, o.limit,
               static_cast<unsigned long long>(o.seed));

  sigset_t mask, original;
  sigemptyset(&mask);
  for (const int s : {SIGCHLD, SIGUSR1, SIGUSR2, SIGINT, SIGTERM}) sigaddset(&mask, s);
  if (sigprocmask(SIG_BLOCK, &mask, &original) < 0) DieErrno("sigprocmask");
  const int sfd = signalfd(-1, &mask, SFD_CLOEXEC | SFD_NONBLOCK);
  if (sfd < 0) DieErrno("signalfd");

  std::mt19937_64 rng(o.seed);
  Direction ab(o, rng), ba(o, rng);
  const double start = Monotonic();
  pid_t pid_a = Spawn(o.cmd_a, ns_a, original);
  pid_t pid_b = Spawn(o.cmd_b, ns_b, original);
  int status_a = -1, status_b = -1;
  bool cut = false;
  bool scheduled_cut_done = o.cut_at_s < 0;
  double cut_began = 0.0;
  std::vector<std::pair<double, double>> cuts;  // UNIX seconds
  const auto set_cut = [&](bool on) {
    if (on == cut) return;
    cut = on;
    const double t = Unix();
    if (on) {
      cut_began = t;
      std::fprintf(stderr, "linkem: cut at %.3f\n", t);
    } else {
      cuts.emplace_back(cut_began, t);
      std::fprintf(stderr, "linkem: link back at %.3f (cut for %.3f s)\n", t, t - cut_began);
    }
  };

  std::vector<uint8_t> buffer(65536);
  while (pid_a > 0 || pid_b > 0) {
    double now = Monotonic();
    if (!scheduled_cut_done) {
      if (!cut && now - start >= o.cut_at_s) set_cut(true);
      if (cut && now - start >= o.cut_at_s + o.cut_for_s) {
        set_cut(false);
        scheduled_cut_done = true;
      }
    }
    double wake = now + 1.0;
    for (const double due : {ab.next_due(), ba.next_due()}) {
      if (due >= 0) wake = std::min(wake, due);
    }
    if (!scheduled_cut_done) wake = std::min(wake, start + o.cut_at_s + (cut ? o.cut_for_s : 0.0));
    pollfd fds[3] = {{tun_a, POLLIN, 0}, {tun_b, POLLIN, 0}, {sfd, POLLIN, 0}};
    const int timeout_ms = static_cast<int>(std::ceil(std::max(0.0, wake - now) * 1e3));
    if (poll(fds, 3, timeout_ms) < 0 && errno != EINTR) DieErrno("poll");
    now = Monotonic();
    for (int i = 0; i < 2; ++i) {
      if (!(fds[i].revents & POLLIN)) continue;
      for (int n = 0; n < 64; ++n) {  // a burst, then the others get their turn
        const ssize_t got = read(fds[i].fd, buffer.data(), buffer.size());
        if (got <= 0) break;
        (i == 0 ? ab : ba).Arrive(std::vector<uint8_t>(buffer.begin(), buffer.begin() + got), now, cut);
      }
    }
    ab.Deliver(tun_b, now, cut);
    ba.Deliver(tun_a, now, cut);
    if (fds[2].revents & POLLIN) {
      signalfd_siginfo si{};
      while (read(sfd, &si, sizeof si) == static_cast<ssize_t>(sizeof si)) {
        if (si.ssi_signo == SIGUSR1) set_cut(true);
        if (si.ssi_signo == SIGUSR2) set_cut(false);
        if (si.ssi_signo == SIGINT || si.ssi_signo == SIGTERM) {
          if (pid_a > 0) kill(pid_a, SIGTERM);
          if (pid_b > 0) kill(pid_b, SIGTERM);
        }
      }
      int st = 0;
      pid_t p;
      while ((p = waitpid(-1, &st, WNOHANG)) > 0) {
        const int code = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
        if (p == pid_a) status_a = code, pid_a = 0;
        if (p == pid_b) status_b = code, pid_b = 0;
      }
    }
  }
  if (cut) set_cut(false);
  const double seconds = Monotonic() - start;
  std::ostringstream j;
  j.setf(std::ios::fixed);
  j.precision(3);
  j << "{\"rate_bps\": " << o.rate_bps << ", \"delay_s\": " << o.delay_s << ", \"loss\": " << o.loss
    << ", \"limit\": " << o.limit << ", \"seed\": " << o.seed << ", \"seconds\": " << seconds
    << ", \"a_status\": " << status_a << ", \"b_status\": " << status_b << ", \"cuts\": [";
  for (size_t i = 0; i < cuts.size(); ++i) {
    j << (i ? ", " : "") << "{\"start_unix\": " << cuts[i].first << ", \"end_unix\": " << cuts[i].second << "}";
  }
  j << "], \"a_to_b\": " << Json(ab.counters(), seconds) << ", \"b_to_a\": " << Json(ba.counters(), seconds)
    << "}";
  std::fprintf(stderr, "linkem: %s\n", j.str().c_str());
  if (!o.stats.empty()) {
    std::ofstream out(o.stats);
    out << j.str() << '\n';
    if (!out) Die("--stats " + o.stats + ": cannot write");
  }
  return status_a == 0 && status_b == 0 ? 0 : 1;
}
