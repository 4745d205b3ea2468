#include "haptic/render_loop.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace doorbench::haptic {
namespace {

// The angles over which a parameter set is checked: the whole door, a little past both stops.
constexpr double kCheckMarginRad = 0.05;

TickRecord prototype_record() {
  return TickRecord{};
}

}  // namespace

std::string RenderLoopOptions::validate() const {
  if (!(rate_hz >= 100.0 && rate_hz <= 4000.0)) {
    std::ostringstream message;
    message << "rate_hz must be in [100, 4000] Hz (got " << rate_hz << ")";
    return message.str();
  }
  if (record_ring_ticks < 16) return "record_ring_ticks must be >= 16";
  if (std::string problem = safety.validate(); !problem.empty()) return "safety: " + problem;
  if (std::string problem = passivity.validate(); !problem.empty()) {
    return "passivity: " + problem;
  }
  return "";
}

RenderLoop::RenderLoop(HapticDevice& device, const DoorMapping& mapping,
                       std::unique_ptr<PlaybackParameters> initial,
                       const RenderLoopOptions& options)
    : device_(device),
      mapping_(mapping),
      options_(options),
      limits_(device.limits()),
      safety_(options.safety, limits_),
      passivity_(options.passivity),
      records_(options.record_ring_ticks, prototype_record()),
      snapshot_(initial ? DoorEventAngles::for_model(initial->model) : DoorEventAngles{}) {
  if (std::string problem = options_.validate(); !problem.empty()) {
    throw std::invalid_argument("render loop: " + problem);
  }
  if (limits_.kinematics != mapping_.kinematics()) {
    throw std::invalid_argument(
        "render loop: the door mapping's kinematics differ from the device " + device_.name() +
        "'s");
  }
  host_renders_inertia_ = !(limits_.max_inertia > 0.0);
  int id = 0;
  if (std::string problem = publish(std::move(initial), &id); !problem.empty()) {
    throw std::invalid_argument("render loop: the first parameter set cannot be played: " +
                                problem);
  }
  parameters_ = mailbox_.take();
  commanded_inertia_ = parameters_->device_inertia;
}

std::string RenderLoop::check(const PlaybackParameters& parameters) const {
  const double theta_max = parameters.model.geometry().theta_max_rad;
  if (!host_renders_inertia_ && (parameters.device_inertia < limits_.min_inertia ||
                                 parameters.device_inertia > limits_.max_inertia)) {
    std::ostringstream message;
    message << "the door's inertia J = " << parameters.model.inertia_kg_m2() << " kg*m^2 needs "
            << parameters.device_inertia << " kg on the device, outside its range ["
            << limits_.min_inertia << ", " << limits_.max_inertia << "] kg";
    return message.str();
  }
  if (parameters.model.term_count() > DoorModel::kMaxTerms) return "too many model terms";
  return check_parameter_set(parameters.model, mapping_, parameters.device_inertia, period_s(),
                             -kCheckMarginRad, theta_max + kCheckMarginRad);
}

std::string RenderLoop::publish(std::unique_ptr<PlaybackParameters> parameters, int* id) {
  if (!parameters) return "no parameter set";
  if (std::string problem = check(*parameters); !problem.empty()) return problem;
  const int published = mailbox_.publish(std::move(parameters));
  if (id) *id = published;
  return "";
}

void RenderLoop::tick(double time_s) noexcept {
  if (const PlaybackParameters* next = mailbox_.take()) {
    parameters_ = next;
    changes_.fetch_add(1, std::memory_order_relaxed);
    if (!host_renders_inertia_ && next->device_inertia != commanded_inertia_) {
      commanded_inertia_ = next->device_inertia;
      device_.command_inertia(commanded_inertia_);
    }
  }
  if (!stop_forwarded_ && stop_requested_.load(std::memory_order_acquire)) {
    safety_.request_stop();
    stop_forwarded_ = true;
  }

  const DeviceSample sample = device_.read();
  const DoorPoint door = mapping_.to_door(sample);
  const DoorModel& model = parameters_->model;
  const int term_count = model.term_count();
  const double model_torque =
      model.torque_Nm(door.theta_rad, door.omega_rad_s,
                      std::span<double>(terms_.data(), static_cast<std::size_t>(term_count)));
  double active_torque = 0.0;
  for (const int term : parameters_->active_terms) active_torque += terms_[term];

  const double dt_s = have_previous_ ? time_s - previous_time_s_ : period_s();
  std::uint32_t events = 0;
  const double passivity_torque =
      passivity_.step(active_torque, door.omega_rad_s, dt_s > 0.0 ? dt_s : period_s(), events);

  Vec3 desired = options_.constraint_on_device
                     ? mapping_.torque_to_device(model_torque + passivity_torque, sample)
                     : mapping_.to_device(model_torque + passivity_torque, sample);
  if (host_renders_inertia_ && have_previous_ && dt_s > 0.0) {
    // The device has no admittance: the host adds the inertia's reaction along the arc.
    const Vec3 tangent = mapping_.tangent_at(door.theta_rad);
    const double acceleration = (sample.velocity - previous_velocity_).dot(tangent) / dt_s;
    desired -= parameters_->device_inertia * acceleration * tangent;
  }
  const SafetyOutput output = safety_.step(SafetyInput{time_s, sample, desired});
  device_.command_force(output.force);
  events |= output.events;
  // A free virtual mass keeps moving when its force is only zeroed: a trip on motion brakes
  // the device at once, and every stop ends braked.
  if (!braked_ && ((output.events & (kEventVelocityTrip | kEventWorkspaceTrip)) != 0 ||
                   output.state == SafetyState::kStopped)) {
    device_.brake();
    braked_ = true;
  }

  have_previous_ = true;
  previous_time_s_ = time_s;
  previous_velocity_ = sample.velocity;
  safety_state_.store(output.state, std::memory_order_release);
  ticks_.fetch_add(1, std::memory_order_relaxed);
  if (output.clipped) clipped_.fetch_add(1, std::memory_order_relaxed);

  status_time_s_.store(time_s, std::memory_order_relaxed);
  status_theta_.store(door.theta_rad, std::memory_order_relaxed);
  status_omega_.store(door.omega_rad_s, std::memory_order_relaxed);
  status_user_force_.store(door.user_force_N, std::memory_order_relaxed);
  status_command_.store(output.force.norm(), std::memory_order_relaxed);
  status_set_.store(parameters_->id, std::memory_order_relaxed);
  snapshot_.publish(time_s, door.theta_rad, door.omega_rad_s);

  TickRecord* record = records_.producer_slot();
  if (!record) {
    dropped_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  record->time_s = time_s;
  record->position = sample.position;
  record->velocity = sample.velocity;
  record->measured_force = sample.measured_force;
  record->commanded_force = output.force;
  record->theta_rad = door.theta_rad;
  record->omega_rad_s = door.omega_rad_s;
  record->user_force_N = door.user_force_N;
  record->model_torque_Nm = model_torque;
  record->passivity_torque_Nm = passivity_torque;
  record->radial_error_m = door.radial_error_m;
  record->axial_error_m = door.axial_error_m;
  record->safety_scale = output.scale;
  record->parameter_set = parameters_->id;
  record->term_count = term_count;
  for (int i = 0; i < term_count; ++i) record->terms_Nm[i] = terms_[i];
  record->events = events;
  record->clipped = output.clipped;
  record->device_sequence = sample.sequence;
  records_.publish();
}

RenderLoopCounters RenderLoop::counters() const noexcept {
  RenderLoopCounters counters;
  counters.ticks = ticks_.load(std::memory_order_relaxed);
  counters.records_dropped = dropped_.load(std::memory_order_relaxed);
  counters.parameter_changes = changes_.load(std::memory_order_relaxed);
  counters.clipped_ticks = clipped_.load(std::memory_order_relaxed);
  return counters;
}

RenderLoop::Status RenderLoop::status() const noexcept {
  return Status{.time_s = status_time_s_.load(std::memory_order_relaxed),
                .theta_rad = status_theta_.load(std::memory_order_relaxed),
                .omega_rad_s = status_omega_.load(std::memory_order_relaxed),
                .user_force_N = status_user_force_.load(std::memory_order_relaxed),
                .commanded_force_N = status_command_.load(std::memory_order_relaxed),
                .parameter_set = status_set_.load(std::memory_order_relaxed)};
}

}  // namespace doorbench::haptic
