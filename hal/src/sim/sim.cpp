#include "sim/sim.hpp"

#include <algorithm>
#include <cstring>

#include "epipole/core/error.hpp"

namespace epipole::hal {

namespace {

constexpr std::size_t kQueueCapacity = 16;

std::uint64_t mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// A uniform number in [0, 1) decided by (seed, sequence, salt) alone.
double chance(std::uint64_t seed, std::uint32_t sequence, std::uint64_t salt) {
  const std::uint64_t h = mix(seed ^ mix(sequence + (salt << 40)));
  return static_cast<double>(h >> 11) * 0x1.0p-53;
}

TriggerConfig own_trigger_config(const CameraConfig& config) {
  validate(config);
  TriggerConfig t;
  t.line = "sim:" + config.device + ":internal";
  t.rate_hz = config.fps;
  t.pulse_width = period_of(config.fps) / 2;
  return t;
}

}  // namespace

// ----------------------------------------------------------------------------------------------

SimTrigger::SimTrigger(TriggerConfig config, VirtualClock& clock)
    : config_(std::move(config)), clock_(clock) {
  validate(config_);
  require(config_.role == TriggerRole::master, "trigger ", config_.line,
          ": the simulated board's trigger is a master");
  period_ = period_of(config_.rate_hz);
}

void SimTrigger::start() {
  schedule_.start(clock_.now(), period_);
  next_emit_ = 0;
  next_report_ = 0;
  next_record_ = 0;
  running_ = true;
}

void SimTrigger::stop() {
  running_ = false;
}

void SimTrigger::set_rate(double rate_hz) {
  config_.rate_hz = with_rate(config_, rate_hz).rate_hz;
  period_ = period_of(rate_hz);
  if (!running_) return;  // start() schedules at the new period
  // The last edge that exists already: given to a camera (they are told ahead of the clock),
  // reported, recorded, or simply passed by the clock.
  const std::uint32_t generated =
      std::max({next_emit_, next_report_, next_record_, schedule_.edges_until(clock_.now())});
  schedule_.change_period(generated == 0 ? 0 : generated - 1, period_);
}

void SimTrigger::connect(SimCamera& camera) {
  for (int i = 0; i < camera_count_; ++i) {
    if (cameras_[i] == &camera) return;
  }
  require(camera_count_ < 4, "trigger ", config_.line, ": at most 4 cameras can be connected");
  cameras_[camera_count_++] = &camera;
  camera.trigger_ = this;
}

void SimTrigger::emit_until(Nanoseconds until) {
  if (!running_) return;
  while (edge(next_emit_).timestamp <= until) {
    const TriggerEdge e = edge(next_emit_);
    for (int i = 0; i < camera_count_ && fires(next_emit_); ++i) cameras_[i]->on_trigger(e);
    ++next_emit_;
  }
  // The cameras are told of edges ahead of time (they schedule their frames); the record, like
  // a real line's, only gets an edge once the clock has passed it, so that it holds the recent
  // edges and not the coming ones.
  const Nanoseconds now = clock_.now();
  next_record_ = std::max(next_record_, schedule_.oldest());
  while (true) {
    const bool edge_due = next_record_ < next_emit_ && edge(next_record_).timestamp <= now;
    if (extra_ && extra_->timestamp <= now &&
        (!edge_due || extra_->timestamp <= edge(next_record_).timestamp)) {
      record(*extra_);
      extra_.reset();
      continue;
    }
    if (!edge_due) break;
    const TriggerEdge e = edge(next_record_);
    if (fires(next_record_) && glitch(SimTriggerGlitchKind::unrecorded, next_record_) == nullptr) {
      record(e);
    }
    if (const SimTriggerGlitch* g = glitch(SimTriggerGlitchKind::extra_edge, next_record_)) {
      extra_ = TriggerEdge{e.sequence, e.timestamp + g->duration, e.clock};
    }
    ++next_record_;
  }
}

TriggerEdge SimTrigger::edge(std::uint32_t sequence) const {
  const SimTriggerGlitch* late = glitch(SimTriggerGlitchKind::late, sequence);
  return {sequence, schedule_.time(sequence) + (late != nullptr ? late->duration : 0),
          ClockId::virtual_clock};
}

const SimTriggerGlitch* SimTrigger::glitch(SimTriggerGlitchKind kind,
                                           std::uint32_t sequence) const {
  for (const SimTriggerGlitch& g : glitches_) {
    if (g.kind == kind && g.sequence == sequence) return &g;
  }
  return nullptr;
}

bool SimTrigger::fires(std::uint32_t sequence) const {
  const Nanoseconds t = schedule_.time(sequence);
  for (const SimTriggerGlitch& g : glitches_) {
    const Nanoseconds from = schedule_.time(g.sequence);
    if (g.kind == SimTriggerGlitchKind::pause && t >= from && t < from + g.duration) return false;
  }
  return true;
}

void SimTrigger::record(const TriggerEdge& edge) {
  if (record_ != nullptr) record_->add(edge);
}

EdgeResult SimTrigger::wait_edge(Nanoseconds timeout) {
  if (!running_) return {EdgeStatus::lost, {}};
  const Nanoseconds deadline = clock_.now() + std::max<Nanoseconds>(timeout, 0);
  next_report_ = std::max(next_report_, schedule_.oldest());
  while (!fires(next_report_)) ++next_report_;
  const TriggerEdge next = edge(next_report_);
  if (next.timestamp <= deadline) {
    clock_.sleep_until(next.timestamp);
    emit_until(next.timestamp);
    ++next_report_;
    return {EdgeStatus::ok, next};
  }
  clock_.sleep_until(deadline);
  emit_until(deadline);
  return {EdgeStatus::timeout, {}};
}

// ----------------------------------------------------------------------------------------------

SimCamera::SimCamera(CameraConfig config, std::shared_ptr<const std::vector<GrayImage>> images,
                     VirtualClock& clock, SimCameraTiming timing)
    : config_(std::move(config)),
      configured_exposure_(config_.exposure),
      configured_gain_(config_.gain),
      name_("sim:" + config_.device),
      images_(std::move(images)),
      clock_(clock),
      timing_(timing),
      own_trigger_(own_trigger_config(config_), clock) {
  require(config_.format == PixelFormat::grey, "camera ", name_, ": pixel format ",
          to_string(config_.format), " is not supported by the simulated camera (grey only)");
  require(images_ != nullptr && !images_->empty(), "camera ", name_, ": no images to replay");
  for (std::size_t i = 0; i < images_->size(); ++i) {
    const GrayImage& image = (*images_)[i];
    require(image.width() == config_.width && image.height() == config_.height, "camera ", name_,
            ": image ", i, " is ", image.width(), "x", image.height(), " but the size setting is ",
            config_.width, "x", config_.height);
  }
  require(timing_.jitter >= 0 && timing_.readout >= 0, "camera ", name_,
          ": jitter and readout must not be negative");
  buffers_.reserve(static_cast<std::size_t>(config_.buffer_count));
  for (int i = 0; i < config_.buffer_count; ++i)
    buffers_.emplace_back(config_.width, config_.height);
  held_.assign(buffers_.size(), 0);
  buffer_truth_.assign(buffers_.size(), 0);
  queue_.resize(kQueueCapacity);
  faults_.reserve(16);
}

void SimCamera::start() {
  require(!disconnected_, "camera ", name_, ": cannot start: device not present");
  if (trigger_ == nullptr || trigger_ == &own_trigger_) {
    require(config_.trigger == TriggerMode::free_running, "camera ", name_,
            ": trigger mode external but no trigger line is connected");
    own_trigger_.connect(*this);
    own_trigger_.start();
  }
  queue_head_ = 0;
  queue_size_ = 0;
  streaming_ = true;
}

void SimCamera::stop() {
  streaming_ = false;
  if (trigger_ == &own_trigger_) own_trigger_.stop();
  queue_size_ = 0;
  std::fill(held_.begin(), held_.end(), 0);
  ++generation_;
}

void SimCamera::set_exposure(Nanoseconds exposure, double gain) {
  validate_exposure(name_, exposure, gain);
  config_.exposure = exposure;
  config_.gain = gain;
  double scale = 1.0;
  if (exposure > 0 && configured_exposure_ > 0) {
    scale *= static_cast<double>(exposure) / static_cast<double>(configured_exposure_);
  }
  if (gain > 0.0 && configured_gain_ > 0.0) scale *= gain / configured_gain_;
  brightness_q16_ = static_cast<std::uint32_t>(std::min(scale, 256.0) * 65536.0 + 0.5);
}

void SimCamera::inject(const SimFault& fault) {
  faults_.push_back(fault);
}

const SimFault* SimCamera::find_fault(SimFaultKind kind, std::uint32_t sequence) const {
  for (const SimFault& f : faults_) {
    if (f.kind != kind) continue;
    const std::uint32_t count = kind == SimFaultKind::drop ? f.count : 1;
    if (sequence >= f.sequence && sequence - f.sequence < count) return &f;
  }
  return nullptr;
}

void SimCamera::on_trigger(const TriggerEdge& edge) {
  if (!streaming_ || disconnected_) return;
  const std::uint32_t s = edge.sequence;
  if (const SimFault* f = find_fault(SimFaultKind::stall, s))
    stalled_until_ = edge.timestamp + f->duration;
  if (edge.timestamp < stalled_until_) return;
  if (find_fault(SimFaultKind::drop, s) != nullptr) return;
  if (rates_.drop > 0.0 && chance(rates_.seed, s, 1) < rates_.drop) return;

  Pending p;
  p.true_sequence = s;
  p.reported_sequence = s;
  p.timestamp = edge.timestamp + timing_.exposure_delay;
  if (timing_.jitter > 0) {
    const double u = chance(timing_.seed, s, 2) * 2.0 - 1.0;
    p.timestamp += static_cast<Nanoseconds>(u * static_cast<double>(timing_.jitter));
  }
  if (const SimFault* f = find_fault(SimFaultKind::skew, s)) p.timestamp += f->duration;
  p.ready = p.timestamp + timing_.readout;
  if (const SimFault* f = find_fault(SimFaultKind::delay, s)) p.ready += f->duration;
  if (rates_.delay > 0.0 && chance(rates_.seed, s, 3) < rates_.delay) {
    p.ready +=
        static_cast<Nanoseconds>(chance(rates_.seed, s, 4) * static_cast<double>(rates_.max_delay));
  }
  if (const SimFault* f = find_fault(SimFaultKind::wrong_sequence, s))
    p.reported_sequence = f->value;
  if (rates_.wrong_sequence > 0.0 && chance(rates_.seed, s, 5) < rates_.wrong_sequence) {
    p.reported_sequence = chance(rates_.seed, s, 6) < 0.5 ? s - 1 : s + 1;
  }
  p.corrupt = find_fault(SimFaultKind::corrupt_pixels, s) != nullptr ||
              (rates_.corrupt_pixels > 0.0 && chance(rates_.seed, s, 7) < rates_.corrupt_pixels);
  p.damaged = find_fault(SimFaultKind::damaged, s) != nullptr ||
              (rates_.damaged > 0.0 && chance(rates_.seed, s, 8) < rates_.damaged);
  p.disconnect = find_fault(SimFaultKind::disconnect, s) != nullptr;
  p.broken = find_fault(SimFaultKind::broken, s) != nullptr;

  if (queue_size_ == queue_.size()) {
    ++overruns_;  // like a driver without a free buffer: the newest frame is lost
    return;
  }
  if (queue_size_ > 0) {  // frames leave in order: one delayed frame holds up those behind it
    const Pending& last = queue_[(queue_head_ + queue_size_ - 1) % queue_.size()];
    p.ready = std::max(p.ready, last.ready);
  }
  queue_[(queue_head_ + queue_size_) % queue_.size()] = p;
  ++queue_size_;
}

void SimCamera::pull_edges(Nanoseconds until) {
  if (trigger_ != nullptr) trigger_->emit_until(until);
}

AcquireResult SimCamera::acquire(Nanoseconds timeout) {
  if (disconnected_ || clock_.now() < broken_until_) return {AcquireStatus::device_lost, {}};
  if (!streaming_) return {AcquireStatus::timeout, {}};
  const Nanoseconds deadline = clock_.now() + std::max<Nanoseconds>(timeout, 0);
  pull_edges(deadline);
  if (queue_size_ == 0 || queue_[queue_head_].ready > deadline) {
    clock_.sleep_until(deadline);
    pull_edges(clock_.now());  // the trigger's record catches up with the clock
    return {AcquireStatus::timeout, {}};
  }
  const Pending p = queue_[queue_head_];
  queue_head_ = (queue_head_ + 1) % queue_.size();
  --queue_size_;
  clock_.sleep_until(p.ready);
  pull_edges(clock_.now());  // the trigger's record catches up with the clock
  if (p.disconnect) {
    disconnected_ = true;
    const SimFault* f = find_fault(SimFaultKind::disconnect, p.true_sequence);
    failing_reopens_ = f != nullptr ? f->value : 0;
    queue_size_ = 0;
    return {AcquireStatus::device_lost, {}};
  }
  if (p.broken) {
    broken_until_ = p.ready + find_fault(SimFaultKind::broken, p.true_sequence)->duration;
    queue_size_ = 0;
    return {AcquireStatus::device_lost, {}};
  }
  if (p.damaged) {  // its buffer requeued
    return corrupt_frame(p.reported_sequence, p.timestamp, ClockId::virtual_clock);
  }
  const auto free = std::find(held_.begin(), held_.end(), 0);
  if (free == held_.end()) {
    ++overruns_;  // every buffer is lent out: the frame is lost
    clock_.sleep_until(deadline);
    return {AcquireStatus::timeout, {}};
  }
  const auto b = static_cast<std::size_t>(free - held_.begin());
  GrayImage& buffer = buffers_[b];
  const GrayImage& source = (*images_)[p.true_sequence % images_->size()];
  for (int y = 0; y < config_.height; ++y) {
    if (p.corrupt) {
      std::uint8_t* row = buffer.view().row(y);
      for (int x = 0; x < config_.width; ++x) {
        row[x] = static_cast<std::uint8_t>(mix((static_cast<std::uint64_t>(p.true_sequence) << 32) ^
                                               static_cast<std::uint64_t>(y * config_.width + x)) >>
                                           56);
      }
    } else if (brightness_q16_ != 1u << 16) {  // exposure or gain changed
      const std::uint8_t* in = source.view().row(y);
      std::uint8_t* out = buffer.view().row(y);
      for (int x = 0; x < config_.width; ++x) {
        const std::uint64_t v = (std::uint64_t{in[x]} * brightness_q16_ + (1u << 15)) >> 16;
        out[x] = static_cast<std::uint8_t>(std::min<std::uint64_t>(v, 255));
      }
    } else {
      std::memcpy(buffer.view().row(y), source.view().row(y),
                  static_cast<std::size_t>(config_.width));
    }
  }
  held_[b] = 1;
  buffer_truth_[b] = p.true_sequence;
  ++delivered_;
  Frame frame;
  frame.gray = buffer.view();
  frame.sequence = p.reported_sequence;
  frame.timestamp = p.timestamp;
  frame.clock = ClockId::virtual_clock;
  frame.buffer = static_cast<int>(b);
  frame.generation = generation_;
  return {AcquireStatus::ok, frame};
}

void SimCamera::release(const Frame& frame) {
  if (!frame.valid() || frame.generation != generation_) return;
  require(static_cast<std::size_t>(frame.buffer) < held_.size() &&
              held_[static_cast<std::size_t>(frame.buffer)] != 0,
          "camera ", name_, ": buffer ", frame.buffer, " released but not lent out");
  held_[static_cast<std::size_t>(frame.buffer)] = 0;
}

std::uint32_t SimCamera::true_sequence(const Frame& frame) const {
  require(frame.valid() && frame.generation == generation_ &&
              static_cast<std::size_t>(frame.buffer) < held_.size() &&
              held_[static_cast<std::size_t>(frame.buffer)] != 0,
          "camera ", name_, ": the frame is not lent out");
  return buffer_truth_[static_cast<std::size_t>(frame.buffer)];
}

void SimCamera::reopen() {
  if (failing_reopens_ > 0) {
    --failing_reopens_;
    throw Error(cat("camera ", name_, ": cannot open: device not present (simulated disconnect)"));
  }
  disconnected_ = false;
  stalled_until_ = 0;
  queue_size_ = 0;
  std::fill(held_.begin(), held_.end(), 0);
  ++generation_;
}

// ----------------------------------------------------------------------------------------------

namespace {
TriggerConfig board_trigger(double rate_hz) {
  TriggerConfig t;
  t.line = "sim";
  t.rate_hz = rate_hz;
  t.pulse_width = rate_hz > 0.0 ? static_cast<Nanoseconds>(2.5e8 / rate_hz) : 1;
  return t;
}
}  // namespace

SimBoard::SimBoard(double rate_hz, std::vector<GrayImage> left_images,
                   std::vector<GrayImage> right_images, SimCameraTiming camera_timing)
    : SimBoard(board_trigger(rate_hz), std::move(left_images), std::move(right_images),
               camera_timing) {}

SimBoard::SimBoard(TriggerConfig trigger_config, std::vector<GrayImage> left_images,
                   std::vector<GrayImage> right_images, SimCameraTiming camera_timing)
    : SimBoard(std::move(trigger_config),
               std::make_shared<const StereoImages>(
                   StereoImages{std::move(left_images), std::move(right_images)}),
               camera_timing) {}

SimBoard::SimBoard(TriggerConfig trigger_config, const std::shared_ptr<const StereoImages>& images,
                   SimCameraTiming camera_timing)
    : trigger(std::move(trigger_config), clock),
      left(images, &images->left),  // sharing ownership of the pair
      right(images, &images->right),
      timing(camera_timing) {
  require(!left->empty() && left->size() == right->size(), "simulated board: ", left->size(),
          " left and ", right->size(), " right images (must be the same, at least one)");
}

std::size_t SimBoard::memory_bytes() const {
  std::size_t bytes = 0;
  for (const auto* side : {left.get(), right.get()}) {
    for (const GrayImage& image : *side) bytes += image.size_bytes();
  }
  return bytes;
}

SimBoard* simulated_board(const Hardware& hardware) {
  return dynamic_cast<SimBoard*>(hardware.backend_board());
}

// ----------------------------------------------------------------------------------------------

std::size_t SimCamera::working_set_bytes() const {
  std::size_t n = held_.capacity() + buffer_truth_.capacity() * sizeof(std::uint32_t) +
                  queue_.capacity() * sizeof(Pending) + faults_.capacity() * sizeof(SimFault);
  for (const GrayImage& b : buffers_) n += b.size_bytes();
  return n;
}

}  // namespace epipole::hal
