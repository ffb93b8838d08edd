#include "robotperf/control/joint_trajectory_controller.hpp"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <stdexcept>

namespace robotperf::control {

Logger stderr_logger(std::string prefix) {
  return [prefix = std::move(prefix)](std::string_view what) {
    std::cerr << prefix << ": " << what << "\n";
  };
}

SplineSegment SplineSegment::make(SplineKind kind, const JointSample& a, const JointSample& b,
                                  double T) {
  SplineSegment s;
  s.kind = kind;
  s.duration_s = T;
  auto& c = s.coefficients;
  if (T <= 0) {  // a point at the start time: jump to it
    c[0] = b.position;
    return s;
  }
  const double dp = b.position - a.position;
  switch (kind) {
    case SplineKind::kLinear:
      c[0] = a.position;
      c[1] = dp / T;
      break;
    case SplineKind::kCubic:
      c[0] = a.position;
      c[1] = a.velocity;
      c[2] = (3 * dp - (2 * a.velocity + b.velocity) * T) / (T * T);
      c[3] = (-2 * dp + (a.velocity + b.velocity) * T) / (T * T * T);
      break;
    case SplineKind::kQuintic: {
      const double T2 = T * T, T3 = T2 * T;
      c[0] = a.position;
      c[1] = a.velocity;
      c[2] = a.acceleration / 2;
      c[3] = (20 * dp - (8 * b.velocity + 12 * a.velocity) * T -
              (3 * a.acceleration - b.acceleration) * T2) /
             (2 * T3);
      c[4] = (-30 * dp + (14 * b.velocity + 16 * a.velocity) * T +
              (3 * a.acceleration - 2 * b.acceleration) * T2) /
             (2 * T3 * T);
      c[5] =
          (12 * dp - 6 * (b.velocity + a.velocity) * T - (a.acceleration - b.acceleration) * T2) /
          (2 * T3 * T2);
      break;
    }
  }
  return s;
}

JointSample SplineSegment::sample(double t) const {
  t = std::clamp(t, 0.0, std::max(duration_s, 0.0));
  const auto& c = coefficients;
  JointSample out;
  out.position = c[0] + t * (c[1] + t * (c[2] + t * (c[3] + t * (c[4] + t * c[5]))));
  out.velocity = c[1] + t * (2 * c[2] + t * (3 * c[3] + t * (4 * c[4] + t * 5 * c[5])));
  out.acceleration = 2 * c[2] + t * (6 * c[3] + t * (12 * c[4] + t * 20 * c[5]));
  return out;
}

JointTrajectoryController::JointTrajectoryController(std::string name,
                                                     JointTrajectoryControllerConfig config,
                                                     Logger log)
    : name_(std::move(name)), config_(std::move(config)), log_(std::move(log)) {
  const std::size_t n = config_.joints.size();
  if (n == 0) throw std::invalid_argument(name_ + ": no joints");
  for (auto* tol : {&config_.path_tolerance, &config_.goal_tolerance}) {
    if (tol->empty()) tol->assign(n, 0.0);
    if (tol->size() != n)
      throw std::invalid_argument(name_ + ": one tolerance per joint is needed");
  }
}

bool JointTrajectoryController::command(const msgs::JointTrajectory& goal, int64_t id) {
  auto reject = [&](const std::string& why) {
    ++rejected_;
    log_("goal rejected: " + why);
    return false;
  };
  const std::size_t n = config_.joints.size();
  if (goal.points.empty()) return reject("no points");
  if (goal.joint_names.size() != n)
    return reject(std::to_string(goal.joint_names.size()) + " joint names, expected " +
                  std::to_string(n));
  std::vector<std::size_t> index(n);  // controller joint -> goal column
  for (std::size_t j = 0; j < n; ++j) {
    std::size_t k = 0;
    while (k < n && goal.joint_names[k] != config_.joints[j]) ++k;
    if (k == n) return reject("joint " + config_.joints[j] + " missing");
    index[j] = k;
  }
  auto prepared = std::make_shared<PreparedTrajectory>();
  prepared->id = id;
  const auto& first = goal.points.front();
  prepared->kind = !first.accelerations.empty() ? SplineKind::kQuintic
                   : !first.velocities.empty()  ? SplineKind::kCubic
                                                : SplineKind::kLinear;
  double previous = -1;
  for (const auto& p : goal.points) {
    const double t = p.time_from_start.sec + p.time_from_start.nanosec * 1e-9;
    if (t < 0 || t <= previous) return reject("time_from_start not increasing");
    previous = t;
    if (p.positions.size() != n) return reject("a point without a position per joint");
    const bool vel = !p.velocities.empty(), acc = !p.accelerations.empty();
    if ((vel && p.velocities.size() != n) || (acc && p.accelerations.size() != n) ||
        (acc && !vel) || vel != (prepared->kind != SplineKind::kLinear) ||
        acc != (prepared->kind == SplineKind::kQuintic)) {
      return reject("points must all give velocities and accelerations for every joint or not");
    }
    std::vector<JointSample> samples(n);
    for (std::size_t j = 0; j < n; ++j) {
      samples[j].position = p.positions[index[j]];
      if (vel) samples[j].velocity = p.velocities[index[j]];
      if (acc) samples[j].acceleration = p.accelerations[index[j]];
      if (!std::isfinite(samples[j].position) || !std::isfinite(samples[j].velocity) ||
          !std::isfinite(samples[j].acceleration))
        return reject("a position, velocity or acceleration is not finite");
    }
    prepared->times_s.push_back(t);
    prepared->points.push_back(std::move(samples));
  }
  prepared->segments.resize(prepared->points.size());
  for (std::size_t i = 1; i < prepared->points.size(); ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      prepared->segments[i].push_back(
          SplineSegment::make(prepared->kind, prepared->points[i - 1][j], prepared->points[i][j],
                              prepared->times_s[i] - prepared->times_s[i - 1]));
    }
  }
  ++accepted_;
  buffer_.write(std::move(prepared));
  return true;
}

void JointTrajectoryController::set_state_publisher(
    std::unique_ptr<RealtimePublisher<State>> publisher) {
  publisher_ = std::move(publisher);
}

std::vector<std::string> JointTrajectoryController::command_interfaces() const {
  std::vector<std::string> out;
  for (const auto& j : config_.joints) out.push_back(j + "/position");
  return out;
}

std::vector<std::string> JointTrajectoryController::state_interfaces() const {
  std::vector<std::string> out;
  for (const auto& j : config_.joints) {
    out.push_back(j + "/position");
    out.push_back(j + "/velocity");
  }
  return out;
}

void JointTrajectoryController::activate(SimulatedHardware& hw) {
  const std::size_t n = config_.joints.size();
  for (const auto& j : config_.joints) {
    position_commands_.push_back(hw.command_interface(j + "/position"));
    position_states_.push_back(hw.state_interface(j + "/position"));
    velocity_states_.push_back(hw.state_interface(j + "/velocity"));
  }
  reference_.assign(n, {});
  first_segment_.assign(n, {});
  feedback_position_.assign(n, 0.0);
  feedback_velocity_.assign(n, 0.0);
  if (publisher_) {
    State& s = publisher_->msg();
    s.joint_names = config_.joints;
    for (auto* p : {&s.reference, &s.error}) {
      p->positions.assign(n, 0.0);
      p->velocities.assign(n, 0.0);
      p->accelerations.assign(n, 0.0);
    }
    s.feedback.positions.assign(n, 0.0);
    s.feedback.velocities.assign(n, 0.0);
    s.output.positions.assign(n, 0.0);
  }
}

void JointTrajectoryController::start_trajectory(double now_s) {
  trajectory_start_s_ = now_s;
  const auto& goal = *trajectory_;
  for (std::size_t j = 0; j < reference_.size(); ++j) {
    // Continue from the reference being followed; from rest at the measured position otherwise.
    JointSample from =
        have_reference_ ? reference_[j] : JointSample{feedback_position_[j], 0.0, 0.0};
    first_segment_[j] = SplineSegment::make(goal.kind, from, goal.points[0][j], goal.times_s[0]);
  }
}

void JointTrajectoryController::hold(const std::vector<double>& positions) {
  trajectory_ = nullptr;
  for (std::size_t j = 0; j < reference_.size(); ++j) reference_[j] = {positions[j], 0.0, 0.0};
  have_reference_ = true;
}

int64_t JointTrajectoryController::update(const UpdateContext& ctx) {
  const std::size_t n = reference_.size();
  for (std::size_t j = 0; j < n; ++j) {
    feedback_position_[j] = *position_states_[j];
    feedback_velocity_[j] = *velocity_states_[j];
  }
  const double now_s = static_cast<double>(ctx.now_ns) * 1e-9;
  int64_t taken = kNoCommand;
  std::shared_ptr<const PreparedTrajectory> incoming = trajectory_;
  if (buffer_.take(incoming)) {
    trajectory_ = incoming;
    taken = trajectory_->id;
    start_trajectory(now_s);
  }
  double t = 0;
  if (trajectory_) {
    const auto& goal = *trajectory_;
    t = now_s - trajectory_start_s_;
    std::size_t i = 0;
    while (i + 1 < goal.times_s.size() && t > goal.times_s[i]) ++i;
    const bool before_first = t <= goal.times_s[0] || i == 0;
    const double end_s = goal.times_s.back();
    for (std::size_t j = 0; j < n; ++j) {
      // From the end on, the last point as given (a linear segment's slope is no velocity
      // there), as ros2_controllers samples past the end.
      reference_[j] = t >= end_s     ? goal.points.back()[j]
                      : before_first ? first_segment_[j].sample(t)
                                     : goal.segments[i][j].sample(t - goal.times_s[i - 1]);
    }
    have_reference_ = true;
    if (t < end_s) {
      for (std::size_t j = 0; j < n; ++j) {
        const double tol = config_.path_tolerance[j];
        if (tol > 0 && std::abs(reference_[j].position - feedback_position_[j]) > tol) {
          ++aborted_;
          log_("path tolerance violated on " + config_.joints[j] + ": goal aborted");
          hold(feedback_position_);
          break;
        }
      }
    } else {
      bool reached = true;
      for (std::size_t j = 0; j < n; ++j) {
        const double tol = config_.goal_tolerance[j];
        const double target = goal.points.back()[j].position;
        const double stopped = config_.stopped_velocity_tolerance;
        if ((tol > 0 && std::abs(target - feedback_position_[j]) > tol) ||
            (stopped > 0 && std::abs(feedback_velocity_[j]) > stopped)) {
          reached = false;
        }
      }
      if (reached) {
        ++succeeded_;
        trajectory_ = nullptr;  // keeps the last reference: holds the goal
      } else if (config_.goal_time_s > 0 && t > end_s + config_.goal_time_s) {
        ++aborted_;
        log_("goal not reached within goal_time: aborted");
        hold(feedback_position_);
      }
    }
  } else if (!have_reference_) {
    hold(feedback_position_);  // first cycle: hold where the robot is
  }
  for (std::size_t j = 0; j < n; ++j) *position_commands_[j] = reference_[j].position;
  if (publisher_ && ctx.observed_command != kNoCommand && publisher_->try_lock()) {
    State& s = publisher_->msg();
    s.header.stamp.sec = static_cast<int32_t>(ctx.observed_command / 1'000'000'000);
    s.header.stamp.nanosec = static_cast<uint32_t>(ctx.observed_command % 1'000'000'000);
    const auto since = static_cast<int64_t>(std::llround(t * 1e9));
    s.reference.time_from_start.sec = static_cast<int32_t>(since / 1'000'000'000);
    s.reference.time_from_start.nanosec = static_cast<uint32_t>(since % 1'000'000'000);
    for (std::size_t j = 0; j < n; ++j) {
      s.reference.positions[j] = reference_[j].position;
      s.reference.velocities[j] = reference_[j].velocity;
      s.reference.accelerations[j] = reference_[j].acceleration;
      s.feedback.positions[j] = feedback_position_[j];
      s.feedback.velocities[j] = feedback_velocity_[j];
      s.error.positions[j] = reference_[j].position - feedback_position_[j];
      s.error.velocities[j] = reference_[j].velocity - feedback_velocity_[j];
      s.output.positions[j] = reference_[j].position;
    }
    publisher_->unlock_and_publish();
  }
  return taken;
}

}  // namespace robotperf::control
