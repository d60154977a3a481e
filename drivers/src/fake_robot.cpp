#include <arpa/inet.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <random>

#include <hil/drivers/error.hpp>
#include <hil/drivers/fake_devices.hpp>

namespace hil::drivers {

struct FakeRobotController::Impl {
  FakeRobotConfig cfg;
  std::shared_ptr<const Scenario> scenario;
  modbus_t* ctx = nullptr;
  modbus_mapping_t* mapping = nullptr;
  int listen_fd = -1;
  int port = 0;
  std::vector<int> clients;
  mutable std::mutex m;  // guards mapping, faults, stats
  ModbusFaults faults;
  Stats stats;
  std::atomic<bool> stop{false};
  std::chrono::steady_clock::time_point start;
  std::mt19937_64 rng;
  ScenarioPoint point;
  unsigned nregs = 0;

  ~Impl() {
    for (int c : clients) ::close(c);
    if (listen_fd >= 0) ::close(listen_fd);
    if (mapping != nullptr) modbus_mapping_free(mapping);
    if (ctx != nullptr) modbus_free(ctx);
  }
  /// Copies holding into input registers (same contents in both tables). Holds m.
  void mirror() { std::copy(mapping->tab_registers, mapping->tab_registers + nregs, mapping->tab_input_registers); }
};

FakeRobotController::FakeRobotController(FakeRobotConfig cfg, std::shared_ptr<const Scenario> scenario) : impl_(std::make_unique<Impl>()) {
  Impl& I = *impl_;
  I.cfg = std::move(cfg);
  I.scenario = std::move(scenario);
  I.faults = I.cfg.faults;
  I.rng.seed(I.cfg.seed);
  I.cfg.map.validate();
  in_addr a{};
  if (::inet_pton(AF_INET, I.cfg.host.c_str(), &a) != 1 || (ntohl(a.s_addr) >> 24) != 127)
    throw ConfigError("host", "'" + I.cfg.host + "': the fake robot controller listens on 127.0.0.0/8 only");
  if (I.cfg.port < 0 || I.cfg.port > 65535) throw ConfigError("port", "must be 0..65535");
  if (!(I.cfg.clock.speed > 0.0)) throw ConfigError("speed", "must be > 0");
  if (!(I.cfg.scenario_step_per_request_s >= 0.0)) throw ConfigError("scenario_step_per_request_s", "must be >= 0");
  unsigned top = 0;
  for (const auto& e : I.cfg.map.entries) {
    top = std::max(top, e.address + register_count(e.type));
    if (e.turns_address >= 0) top = std::max(top, static_cast<unsigned>(e.turns_address) + 1);
  }
  I.nregs = top;
  I.mapping = modbus_mapping_new(0, 0, static_cast<int>(top), static_cast<int>(top));
  if (I.mapping == nullptr) throw DeviceError("fake robot controller: cannot allocate the register mapping");
  I.ctx = modbus_new_tcp(I.cfg.host.c_str(), I.cfg.port);
  if (I.ctx == nullptr) throw DeviceError(std::string("fake robot controller: modbus_new_tcp: ") + modbus_strerror(errno));
  I.listen_fd = modbus_tcp_listen(I.ctx, 8);
  if (I.listen_fd < 0)
    throw DeviceError("fake robot controller: cannot listen on " + I.cfg.host + ":" + std::to_string(I.cfg.port) + ": " +
                      modbus_strerror(errno));
  sockaddr_in sa{};
  socklen_t len = sizeof sa;
  ::getsockname(I.listen_fd, reinterpret_cast<sockaddr*>(&sa), &len);
  I.port = ntohs(sa.sin_port);
  const std::vector<double> zeros(I.cfg.map.joint_count(), 0.0);
  encode_state(I.cfg.map, zeros, Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity(),
               std::span<std::uint16_t>(I.mapping->tab_registers, top));
  I.mirror();
}

FakeRobotController::~FakeRobotController() { stop(); }

int FakeRobotController::port() const noexcept { return impl_->port; }

void FakeRobotController::start() {
  if (thread_.joinable()) return;
  impl_->stop = false;
  impl_->start = std::chrono::steady_clock::now();
  thread_ = std::jthread([this] { run(); });
}

void FakeRobotController::stop() noexcept {
  impl_->stop = true;
  if (thread_.joinable()) thread_.join();
}

void FakeRobotController::set_state(std::span<const double> joints, const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  std::lock_guard lk(impl_->m);
  encode_state(impl_->cfg.map, joints, p, q, std::span<std::uint16_t>(impl_->mapping->tab_registers, impl_->nregs));
  impl_->mirror();
}

void FakeRobotController::set_faults(const ModbusFaults& f) {
  std::lock_guard lk(impl_->m);
  impl_->faults = f;
}

FakeRobotController::Stats FakeRobotController::stats() const {
  std::lock_guard lk(impl_->m);
  return impl_->stats;
}

void FakeRobotController::run() noexcept {
  using Clock = std::chrono::steady_clock;
  Impl& I = *impl_;
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::vector<pollfd> fds;
  std::uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
  const int header = modbus_get_header_length(I.ctx);
  while (!I.stop.load()) {
    fds.clear();
    fds.push_back({I.listen_fd, POLLIN, 0});
    for (int c : I.clients) fds.push_back({c, POLLIN, 0});
    if (::poll(fds.data(), fds.size(), 20) <= 0) continue;
    if ((fds[0].revents & POLLIN) != 0) {
      const int c = ::accept(I.listen_fd, nullptr, nullptr);
      if (c >= 0) {
        I.clients.push_back(c);
        std::lock_guard lk(I.m);
        ++I.stats.connections;
      }
    }
    for (std::size_t k = 1; k < fds.size(); ++k) {
      if (fds[k].revents == 0) continue;
      const int c = fds[k].fd;
      modbus_set_socket(I.ctx, c);
      const int rc = modbus_receive(I.ctx, query);
      if (rc < 0) {
        ::close(c);
        I.clients.erase(std::remove(I.clients.begin(), I.clients.end(), c), I.clients.end());
        continue;
      }
      if (rc == 0) continue;
      const double t = std::chrono::duration<double>(Clock::now() - I.start).count();
      ModbusFaults f;
      {
        std::lock_guard lk(I.m);
        ++I.stats.requests;
        f = I.faults;
      }
      bool silent = f.silent_now;
      for (const auto& w : f.silent) silent = silent || w.contains(t);
      if (silent) {
        std::lock_guard lk(I.m);
        ++I.stats.ignored_silent;
        continue;
      }
      const std::uint8_t function = query[header];
      const bool is_write = function == 0x05 || function == 0x06 || function == 0x0F || function == 0x10 || function == 0x16 ||
                            function == 0x17;
      if (is_write) {
        modbus_reply_exception(I.ctx, query, MODBUS_EXCEPTION_ILLEGAL_FUNCTION);
        std::lock_guard lk(I.m);
        ++I.stats.writes_refused;
        continue;
      }
      double delay = f.extra_delay_s;
      bool slow = false, exception = false;
      {
        std::lock_guard lk(I.m);
        if (f.slow_fraction > 0.0 && uni(I.rng) < f.slow_fraction) slow = true;
        if (f.exception_fraction > 0.0 && uni(I.rng) < f.exception_fraction) exception = true;
      }
      for (const auto& w : f.exception_windows) exception = exception || w.contains(t);
      if (slow) {
        delay += f.slow_delay_s;
        std::lock_guard lk(I.m);
        ++I.stats.slow;
      }
      if (delay > 0.0) std::this_thread::sleep_for(std::chrono::nanoseconds(static_cast<std::int64_t>(delay * 1e9)));
      if (exception) {
        modbus_reply_exception(I.ctx, query, MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY);
        std::lock_guard lk(I.m);
        ++I.stats.exceptions;
        continue;
      }
      std::lock_guard lk(I.m);
      if (I.scenario) {
        const double t_scenario = I.cfg.scenario_step_per_request_s > 0.0
                                      ? I.cfg.scenario_step_per_request_s * static_cast<double>(I.stats.requests - 1)
                                      : I.cfg.clock.scenario_time(std::chrono::duration<double>(Clock::now() - I.start).count());
        I.scenario->at(t_scenario, I.point);
        encode_state(I.cfg.map, I.point.joints_rad, I.point.p_base_tcp_m, I.point.q_base_tcp,
                     std::span<std::uint16_t>(I.mapping->tab_registers, I.nregs));
        I.mirror();
      }
      if (modbus_reply(I.ctx, query, rc, I.mapping) >= 0) ++I.stats.replies;
    }
  }
}

}  // namespace hil::drivers
