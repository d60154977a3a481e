#include <algorithm>
#include <condition_variable>
#include <ctime>
#include <deque>
#include <mutex>

#include <hil/drivers/can_channel.hpp>

namespace hil::drivers {

std::int64_t realtime_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

const char* to_string(IoStatus s) noexcept {
  switch (s) {
    case IoStatus::ok: return "ok";
    case IoStatus::timeout: return "timeout";
    case IoStatus::closed: return "closed";
    case IoStatus::error: return "error";
  }
  return "?";
}

namespace {
class LoopbackEndpoint;
}

struct CanLoopbackBus::Impl {
  std::mutex m;
  std::vector<LoopbackEndpoint*> endpoints;
  bool closed = false;
};

namespace {

class LoopbackEndpoint final : public CanChannel {
 public:
  LoopbackEndpoint(std::shared_ptr<CanLoopbackBus> bus, CanLoopbackBus::Impl* impl, CanChannelOptions opt)
      : bus_(std::move(bus)), impl_(impl), opt_(std::move(opt)) {
    std::lock_guard lk(impl_->m);
    impl_->endpoints.push_back(this);
  }
  ~LoopbackEndpoint() override {
    std::lock_guard lk(impl_->m);
    auto& v = impl_->endpoints;
    v.erase(std::remove(v.begin(), v.end(), this), v.end());
  }

  IoStatus send(const CanFrame& frame, std::chrono::nanoseconds /*timeout*/) noexcept override {
    if (const char* p = frame_problem(frame)) {
      std::lock_guard lk(impl_->m);
      last_error_ = p;
      ++stats_.tx_failed;
      return IoStatus::error;
    }
    if (frame.fd && !opt_.fd) {
      std::lock_guard lk(impl_->m);
      last_error_ = "CAN FD frame on a channel opened without fd";
      ++stats_.tx_failed;
      return IoStatus::error;
    }
    CanFrame f = frame;
    f.t_ns = realtime_ns();
    f.stamp = StampSource::software;
    std::lock_guard lk(impl_->m);
    if (impl_->closed) return IoStatus::closed;
    ++stats_.tx_frames;
    for (auto* ep : impl_->endpoints) {
      if (ep == this && !opt_.receive_own) continue;
      ep->deliver(f);
    }
    return IoStatus::ok;
  }

  IoStatus receive(CanFrame& frame, std::chrono::nanoseconds timeout) noexcept override {
    std::unique_lock lk(impl_->m);
    if (!cv_.wait_for(lk, timeout, [&] { return !q_.empty() || impl_->closed; })) return IoStatus::timeout;
    if (q_.empty()) return IoStatus::closed;
    frame = q_.front();
    q_.pop_front();
    ++stats_.rx_frames;
    if (frame.error) ++stats_.error_frames;
    return IoStatus::ok;
  }

  CanChannelStats stats() const noexcept override {
    std::lock_guard lk(impl_->m);
    return stats_;
  }
  std::string name() const override { return bus_->name(); }
  std::string last_error() const override {
    std::lock_guard lk(impl_->m);
    return last_error_;
  }

  /// Called with the bus mutex held.
  void deliver(const CanFrame& f) {
    if (f.error ? (f.id & opt_.error_mask) == 0 : !passes(opt_.filters, f)) return;
    if (f.fd && !opt_.fd) return;
    if (q_.size() >= opt_.rx_queue) {
      ++stats_.rx_dropped;
      return;
    }
    q_.push_back(f);
    cv_.notify_one();
  }
  void wake() { cv_.notify_all(); }

 private:
  std::shared_ptr<CanLoopbackBus> bus_;
  CanLoopbackBus::Impl* impl_;
  CanChannelOptions opt_;
  std::condition_variable cv_;
  std::deque<CanFrame> q_;
  CanChannelStats stats_;
  std::string last_error_;
};

}  // namespace

CanLoopbackBus::CanLoopbackBus(std::string name) : name_(std::move(name)), impl_(std::make_unique<Impl>()) {}
CanLoopbackBus::~CanLoopbackBus() = default;

std::shared_ptr<CanLoopbackBus> CanLoopbackBus::create(std::string name) {
  return std::shared_ptr<CanLoopbackBus>(new CanLoopbackBus(std::move(name)));
}

std::unique_ptr<CanChannel> CanLoopbackBus::open(CanChannelOptions options) {
  return std::make_unique<LoopbackEndpoint>(shared_from_this(), impl_.get(), std::move(options));
}

void CanLoopbackBus::close() {
  std::lock_guard lk(impl_->m);
  impl_->closed = true;
  for (auto* ep : impl_->endpoints) ep->wake();
}

}  // namespace hil::drivers
