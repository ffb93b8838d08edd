// Controllers, simulated hardware and the controller manager loop against analytic expectations.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <numbers>
#include <string>
#include <thread>
#include <vector>

#include "robotperf/control/controller_manager.hpp"
#include "robotperf/control/diff_drive_controller.hpp"
#include "robotperf/control/forward_command_controller.hpp"
#include "robotperf/control/joint_trajectory_controller.hpp"
#include "robotperf/msgs/type_support.hpp"

namespace robotperf::control {
namespace {

constexpr int64_t kSecond = 1'000'000'000;

TEST(Spline, LinearCubicQuinticMatchTheirClosedForms) {
  const JointSample a{0.0, 0.0, 0.0}, b{1.0, 0.0, 0.0};
  const auto linear = SplineSegment::make(SplineKind::kLinear, a, b, 4.0);
  EXPECT_NEAR(linear.sample(1.0).position, 0.25, 1e-12);
  EXPECT_NEAR(linear.sample(1.0).velocity, 0.25, 1e-12);
  // Rest to rest: cubic p(t) = 3 s^2 - 2 s^3, s = t / T.
  const auto cubic = SplineSegment::make(SplineKind::kCubic, a, b, 4.0);
  EXPECT_NEAR(cubic.sample(1.0).position, 3 * 0.0625 - 2 * 0.015625, 1e-12);
  EXPECT_NEAR(cubic.sample(2.0).velocity, 1.5 / 4.0, 1e-12);
  // Quintic p(t) = 10 s^3 - 15 s^4 + 6 s^5: half way 0.5, velocity 15/8 / T.
  const auto quintic = SplineSegment::make(SplineKind::kQuintic, a, b, 4.0);
  EXPECT_NEAR(quintic.sample(2.0).position, 0.5, 1e-12);
  EXPECT_NEAR(quintic.sample(2.0).velocity, 15.0 / 8.0 / 4.0, 1e-12);
  EXPECT_NEAR(quintic.sample(2.0).acceleration, 0.0, 1e-12);
  EXPECT_NEAR(quintic.sample(1.0).position, 10 * 0.015625 - 15 * 0.00390625 + 6 * 0.0009765625,
              1e-12);
  // Ends: position, velocity and acceleration matched; clamped beyond.
  EXPECT_NEAR(quintic.sample(4.0).position, 1.0, 1e-12);
  EXPECT_NEAR(quintic.sample(4.0).velocity, 0.0, 1e-12);
  EXPECT_NEAR(quintic.sample(9.0).position, 1.0, 1e-12);
  // Non-zero boundary velocities are honoured by the cubic.
  const auto moving = SplineSegment::make(SplineKind::kCubic, {0, 1, 0}, {2, -1, 0}, 2.0);
  EXPECT_NEAR(moving.sample(0.0).velocity, 1.0, 1e-12);
  EXPECT_NEAR(moving.sample(2.0).velocity, -1.0, 1e-12);
  EXPECT_NEAR(moving.sample(2.0).position, 2.0, 1e-12);
}

msgs::JointTrajectory goal(double target, double seconds, bool with_rates = true) {
  msgs::JointTrajectory g;
  g.joint_names = {"joint2", "joint1"};  // another order than the controller's
  msgs::JointTrajectoryPoint p;
  p.positions = {target, -target};
  if (with_rates) {
    p.velocities = {0, 0};
    p.accelerations = {0, 0};
  }
  p.time_from_start.sec = static_cast<int32_t>(seconds);
  g.points.push_back(p);
  return g;
}

struct Rig {
  explicit Rig(HardwareConfig hw, double rate = 100.0)
      : manager(make_hardware(hw), LoopConfig{"test", rate, -1, 0, 10'000}) {}
  // Steps `seconds` of simulated time at the manager's rate.
  void run(double seconds) {
    const auto period = static_cast<int64_t>(1e9 / manager.config().update_rate_hz);
    for (int64_t end = now + static_cast<int64_t>(seconds * 1e9); now < end; now += period)
      manager.cycle(now);
  }
  ControllerManager manager;
  int64_t now = 1000 * kSecond;
};

TEST(JointTrajectoryController, ReachesTheGoalOnTheQuinticAndHoldsIt) {
  HardwareConfig hw;
  hw.position_time_constant_s = 0.0;
  Rig rig(hw);
  JointTrajectoryControllerConfig c;
  c.goal_tolerance = {0.01, 0.01};
  c.goal_time_s = 1.0;
  auto jtc = std::make_shared<JointTrajectoryController>("jtc", c, [](std::string_view) {});
  rig.manager.add_controller(jtc);
  rig.run(0.05);
  ASSERT_TRUE(jtc->command(goal(0.785, 4.0), 42));
  rig.run(2.0);  // half way on the quintic (joint1 is the goal's second column)
  EXPECT_NEAR(jtc->reference()[0].position, -0.785 * 0.5, 0.02);
  rig.run(2.5);
  const double* joint1 = rig.manager.hardware().state_interface("joint1/position");
  const double* joint2 = rig.manager.hardware().state_interface("joint2/position");
  EXPECT_NEAR(*joint1, -0.785, 1e-6);
  EXPECT_NEAR(*joint2, 0.785, 1e-6);
  EXPECT_EQ(jtc->goals_succeeded(), 1u);
  EXPECT_EQ(jtc->goals_aborted(), 0u);
  EXPECT_FALSE(jtc->active());
}

TEST(JointTrajectoryController, AbortsAGoalTheLaggingRobotCannotReachInTime) {
  HardwareConfig hw;
  hw.position_time_constant_s = 5.0;  // far too slow for the goal
  Rig rig(hw);
  JointTrajectoryControllerConfig c;
  c.goal_tolerance = {0.01, 0.01};
  c.goal_time_s = 0.5;
  auto jtc = std::make_shared<JointTrajectoryController>("jtc", c, [](std::string_view) {});
  rig.manager.add_controller(jtc);
  ASSERT_TRUE(jtc->command(goal(1.0, 1.0), 7));
  rig.run(2.0);
  EXPECT_EQ(jtc->goals_aborted(), 1u);
  EXPECT_FALSE(jtc->active());
  // Holding where the robot was, not at the goal.
  EXPECT_LT(std::abs(jtc->reference()[1].position), 0.9);
}

TEST(JointTrajectoryController, RejectsMalformedGoals) {
  std::vector<std::string> logged;
  JointTrajectoryController jtc("jtc", {}, [&](std::string_view s) { logged.emplace_back(s); });
  auto wrong_joint = goal(1.0, 1.0);
  wrong_joint.joint_names = {"joint1", "elbow"};
  EXPECT_FALSE(jtc.command(wrong_joint, 1));
  msgs::JointTrajectory no_points;
  no_points.joint_names = {"joint1", "joint2"};
  EXPECT_FALSE(jtc.command(no_points, 2));
  EXPECT_EQ(jtc.goals_rejected(), 2u);
  ASSERT_EQ(logged.size(), 2u);
  EXPECT_NE(logged[0].find("joint2 missing"), std::string::npos) << logged[0];
}

// Past its end a goal's reference is its last point as given: a position-only (linear) goal
// leaves no velocity behind, so a next goal to the same place starts at rest and stays there.
TEST(JointTrajectoryController, LinearGoalEndsAtRest) {
  HardwareConfig hw;
  hw.position_time_constant_s = 0.0;
  Rig rig(hw);
  JointTrajectoryControllerConfig c;
  c.goal_tolerance = {0.01, 0.01};
  auto jtc = std::make_shared<JointTrajectoryController>("jtc", c, [](std::string_view) {});
  rig.manager.add_controller(jtc);
  rig.run(0.05);
  ASSERT_TRUE(jtc->command(goal(1.0, 1.0, false), 1));
  rig.run(3.0);
  EXPECT_EQ(jtc->goals_succeeded(), 1u);
  EXPECT_EQ(jtc->reference()[1].position, 1.0);
  EXPECT_EQ(jtc->reference()[1].velocity, 0.0);
  ASSERT_TRUE(jtc->command(goal(1.0, 1.0), 2));
  double furthest = 0;
  for (int i = 0; i < 150; ++i) {
    rig.run(0.01);
    furthest = std::max(furthest, std::abs(jtc->reference()[1].position - 1.0));
  }
  EXPECT_LT(furthest, 1e-9);
  EXPECT_EQ(jtc->goals_succeeded(), 2u);
}

// A velocity or acceleration that is not finite is refused with the goal: kept, it made the
// reference NaN, which the robot ignores, and every later goal started from NaN.
TEST(JointTrajectoryController, RejectsNonFiniteRates) {
  JointTrajectoryController jtc("jtc", {}, [](std::string_view) {});
  auto nan_velocity = goal(1.0, 1.0);
  nan_velocity.points[0].velocities[0] = std::nan("");
  EXPECT_FALSE(jtc.command(nan_velocity, 1));
  auto infinite_acceleration = goal(1.0, 1.0);
  infinite_acceleration.points[0].accelerations[1] = INFINITY;
  EXPECT_FALSE(jtc.command(infinite_acceleration, 2));
  EXPECT_EQ(jtc.goals_rejected(), 2u);
  EXPECT_EQ(jtc.goals_accepted(), 0u);
}

// stopped_velocity_tolerance 0 is "not checked", as the other tolerances' 0 (and as in
// ros2_controllers), not "exactly still": a lagging joint still creeping at the goal reaches it.
TEST(JointTrajectoryController, ZeroStoppedVelocityToleranceIsNotChecked) {
  HardwareConfig hw;  // first-order lag: the joints approach the goal without ever stopping
  Rig rig(hw);
  JointTrajectoryControllerConfig c;
  c.goal_tolerance = {0.01, 0.01};
  c.goal_time_s = 1.0;
  c.stopped_velocity_tolerance = 0.0;
  auto jtc = std::make_shared<JointTrajectoryController>("jtc", c, [](std::string_view) {});
  rig.manager.add_controller(jtc);
  rig.run(0.05);
  ASSERT_TRUE(jtc->command(goal(0.785, 1.0), 1));
  rig.run(2.0);
  EXPECT_EQ(jtc->goals_succeeded(), 1u);
  EXPECT_EQ(jtc->goals_aborted(), 0u);
}

TEST(SpeedLimits, AccelerationThenVelocity) {
  SpeedLimits l{true, -1.0, 1.0, true, -1.0, 1.0};
  EXPECT_DOUBLE_EQ(l.limit(5.0, 0.0, 0.1), 0.1);   // +1 m/s^2 over 0.1 s
  EXPECT_DOUBLE_EQ(l.limit(0.0, 0.5, 0.1), 0.4);   // deceleration limited too
  EXPECT_DOUBLE_EQ(l.limit(5.0, 0.95, 0.1), 1.0);  // then clamped to the velocity limit
  EXPECT_DOUBLE_EQ(l.limit(0.3, 0.25, 0.1), 0.3);  // within limits: unchanged
  const SpeedLimits none;
  EXPECT_DOUBLE_EQ(none.limit(5.0, 0.0, 0.1), 5.0);
}

TEST(Odometry, Rk2FollowsACircleOfKnownRadius) {
  Odometry odom;
  const double v = 1.0, w = 0.5, radius = v / w;
  const int quarter = 1000;
  const double dt = std::numbers::pi / 2 / w / quarter;
  for (int i = 0; i < quarter; ++i) odom.integrate(v, w, dt);
  EXPECT_NEAR(odom.x(), radius, 1e-6);  // a left turn about (0, R)
  EXPECT_NEAR(odom.y(), radius, 1e-6);
  EXPECT_NEAR(odom.heading(), std::numbers::pi / 2, 1e-9);
  for (int i = 0; i < 3 * quarter; ++i) odom.integrate(v, w, dt);
  EXPECT_NEAR(odom.x(), 0.0, 1e-6);
  EXPECT_NEAR(odom.y(), 0.0, 1e-6);
}

TEST(DiffDriveController, WheelCommandsOdometryAndTimeout) {
  HardwareConfig hw;
  hw.type = "diffbot";
  Rig rig(hw, 10.0);
  DiffDriveControllerConfig c;  // separation 0.10 m, radius 0.015 m, no limits
  c.cmd_vel_timeout_s = 0.5;
  auto dd = std::make_shared<DiffDriveController>("dd", c);
  rig.manager.add_controller(dd);
  dd->command({1, 0.3, 0.2, rig.now});
  rig.run(0.1);
  auto& h = rig.manager.hardware();
  EXPECT_NEAR(*h.command_interface("left_wheel_joint/velocity"), (0.3 - 0.01) / 0.015, 1e-9);
  EXPECT_NEAR(*h.command_interface("right_wheel_joint/velocity"), (0.3 + 0.01) / 0.015, 1e-9);
  rig.run(0.3);
  // Odometry and the simulated robot agree: the same twist, RK2 against the exact arc.
  EXPECT_NEAR(dd->odometry().x(), h.base_pose()->x, 1e-4);
  EXPECT_NEAR(dd->odometry().y(), h.base_pose()->y, 1e-4);
  rig.run(0.5);  // no new command for longer than the timeout
  EXPECT_EQ(dd->timeouts(), 1u);
  EXPECT_DOUBLE_EQ(*h.command_interface("left_wheel_joint/velocity"), 0.0);
}

// Settings that would leave the robot unable to stop, or make the timeout undefined in
// nanoseconds, are refused when the controller is made.
TEST(DiffDriveController, RefusesLimitsAndTimeoutsItCannotHonour) {
  auto make = [](const std::function<void(DiffDriveControllerConfig&)>& change) {
    DiffDriveControllerConfig c;
    change(c);
    return DiffDriveController("dd", c);
  };
  EXPECT_NO_THROW(make([](auto&) {}));
  EXPECT_THROW(make([](auto& c) {
                 c.linear.has_acceleration_limits = true;
                 c.linear.min_acceleration = 0.5;  // the speed could only ever grow
                 c.linear.max_acceleration = 1.0;
               }),
               std::invalid_argument);
  EXPECT_THROW(make([](auto& c) {
                 c.angular.has_velocity_limits = true;
                 c.angular.max_velocity = std::nan("");
               }),
               std::invalid_argument);
  for (const double timeout : {-1.0, std::nan(""), 1e300}) {
    EXPECT_THROW(make([&](auto& c) { c.cmd_vel_timeout_s = timeout; }), std::invalid_argument)
        << timeout;
  }
}

std::shared_ptr<msgs::Float64MultiArray> array_command(std::vector<double> data, int64_t id) {
  auto m = std::make_shared<msgs::Float64MultiArray>();
  m->data = std::move(data);
  msgs::MessageTraits<msgs::Float64MultiArray>::set_id_ns(*m, id);
  return m;
}

TEST(ForwardCommandController, CopiesCommandsAndRejectsAWrongSize) {
  Rig rig(HardwareConfig{"rrbot_multi_interface"});
  std::vector<std::string> logged;
  auto fcc = std::make_shared<ForwardCommandController>(
      "fcc", ForwardCommandControllerConfig{{"joint1", "joint2"}, "velocity"},
      [&](std::string_view s) { logged.emplace_back(s); });
  rig.manager.add_controller(fcc);
  fcc->command(array_command({0.5, -0.25}, 11));
  rig.run(1.0);  // 100 cycles at 0.5 rad/s
  const auto& h = rig.manager.hardware();
  EXPECT_NEAR(*h.state_interface("joint1/position"), 0.5 * 0.99, 1e-9);  // read lags one cycle
  EXPECT_NEAR(*h.state_interface("joint2/velocity"), -0.25, 1e-12);
  fcc->command(array_command({1.0, 2.0, 3.0}, 12));
  rig.run(0.1);
  EXPECT_EQ(fcc->rejected(), 1u);
  ASSERT_EQ(logged.size(), 1u);
  EXPECT_NE(logged[0].find("does not match"), std::string::npos);
  EXPECT_NEAR(*h.state_interface("joint2/velocity"), -0.25, 1e-12);  // nothing actuated
}

TEST(Hardware, MultiInterfaceTakesOneCommandKindPerJoint) {
  auto hw = make_hardware({"rrbot_multi_interface"});
  hw->claim({"joint1/acceleration", "joint2/acceleration"});
  EXPECT_THROW(hw->claim({"joint1/position"}), std::invalid_argument);
  *hw->command_interface("joint1/acceleration") = 2.0;
  for (int i = 0; i < 100; ++i) hw->write(0.01);
  hw->read();
  EXPECT_NEAR(*hw->state_interface("joint1/velocity"), 2.0, 1e-12);
  EXPECT_NEAR(*hw->state_interface("joint1/position"), 2.0 * 0.01 * 0.01 * 5050, 1e-9);
  EXPECT_THROW(make_hardware({"hexapod"}), std::invalid_argument);
  EXPECT_THROW(hw->command_interface("joint3/position"), std::invalid_argument);
}

TEST(MessageId, Float64MultiArrayCarriesItsIdInTheLayoutLabel) {
  const auto& ts = msgs::type_support<msgs::Float64MultiArray>();
  ASSERT_TRUE(ts.stamped());
  msgs::Float64MultiArray m;
  m.data = {1.0, 2.0};
  EXPECT_EQ(ts.stamp_ns(&m), -1);
  auto copy = ts.copy_with_stamp_ns(&m, 1'700'000'000'123'456'789);
  const auto& c = *static_cast<const msgs::Float64MultiArray*>(copy.get());
  EXPECT_EQ(ts.stamp_ns(&c), 1'700'000'000'123'456'789);
  ASSERT_EQ(c.layout.dim.size(), 1u);
  EXPECT_EQ(c.layout.dim[0].size, 2u);  // the layout still describes the data
  EXPECT_EQ(c.data, m.data);
}

TEST(ControllerManager, LoopRunsAtAbsoluteDeadlinesAndStops) {
  ControllerManager manager(make_hardware({"rrbot_multi_interface"}),
                            LoopConfig{"loop", 1000.0, -1, 0, 100'000});
  auto fcc = std::make_shared<ForwardCommandController>(
      "fcc", ForwardCommandControllerConfig{{"joint1", "joint2"}, "position"});
  manager.add_controller(fcc);
  fcc->command(array_command({0.1, 0.2}, 5));
  manager.start();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  manager.stop();
  const LoopReport r = manager.report();
  ASSERT_GT(r.cycles, 50u);  // ~300 on an idle machine; a loaded one still runs many
  ASSERT_EQ(r.records.size(), r.cycles);
  uint64_t skipped = 0;
  for (std::size_t k = 0; k < r.records.size(); ++k) {
    const auto& c = r.records[k];
    EXPECT_GE(c.wake_ns, c.deadline_ns);
    EXPECT_LE(c.wake_ns, c.read_end_ns);
    EXPECT_LE(c.update_end_ns, c.write_end_ns);
    if (k > 0) {
      // On the 1 ms grid; periods the loop overslept are skipped, not caught up.
      const int64_t step = c.deadline_ns - r.records[k - 1].deadline_ns;
      EXPECT_EQ(step % 1000000, 0) << step;
      EXPECT_GE(step, 1000000);
      EXPECT_LE(c.deadline_ns, r.records[k - 1].write_end_ns + 1000000)
          << "not skipped: not overrun";
      skipped += static_cast<uint64_t>(step / 1000000 - 1);
    }
  }
  EXPECT_GE(r.deadline_misses, skipped);
  ASSERT_EQ(r.writes.size(), 1u);
  EXPECT_EQ(r.writes[0].command_id, 5);
  EXPECT_DOUBLE_EQ(*manager.hardware().state_interface("joint2/position"), 0.2);
}

// A controller whose update takes `stall_ms` in cycle `stall_cycle`.
class StallingController final : public Controller {
 public:
  StallingController(uint64_t stall_cycle, int stall_ms)
      : stall_cycle_(stall_cycle), stall_ms_(stall_ms) {}
  const std::string& name() const override { return name_; }
  std::vector<std::string> command_interfaces() const override { return {}; }
  std::vector<std::string> state_interfaces() const override { return {}; }
  void activate(SimulatedHardware&) override {}
  int64_t update(const UpdateContext& ctx) override {
    if (ctx.cycle == stall_cycle_)
      std::this_thread::sleep_for(std::chrono::milliseconds(stall_ms_));
    return kNoCommand;
  }

 private:
  std::string name_ = "stall";
  uint64_t stall_cycle_;
  int stall_ms_;
};

// A cycle woken on time whose own work overruns the next deadline skips the periods it ran over,
// as ros2_control's loop does: the next cycle is not run at once for a deadline already passed.
TEST(ControllerManager, OverrunningCycleSkipsThePeriodsItRanOver) {
  constexpr int64_t kPeriod = 10'000'000;  // 100 Hz
  ControllerManager manager(make_hardware({}), LoopConfig{"loop", 100.0, -1, 0, 1000});
  manager.add_controller(std::make_shared<StallingController>(3, 25));
  manager.start();
  std::this_thread::sleep_for(std::chrono::milliseconds(150));
  manager.stop();
  const LoopReport r = manager.report();
  ASSERT_GT(r.records.size(), 4u);
  const auto& stalled = r.records[3];
  ASSERT_GE(stalled.write_end_ns - stalled.wake_ns, 25'000'000);
  // Ended at least 25 ms after its deadline: the two deadlines it ran over are not run.
  EXPECT_GE(r.records[4].deadline_ns, stalled.deadline_ns + 3 * kPeriod);
  EXPECT_GE(r.deadline_misses, 3u);  // the late cycle and the two periods skipped
}

TEST(ControllerManager, BadLoopSettingsAreRefused) {
  EXPECT_THROW(ControllerManager(make_hardware({}), LoopConfig{"x", 0.0, -1, 0, 10}),
               std::invalid_argument);
  EXPECT_THROW(ControllerManager(make_hardware({}), LoopConfig{"x", 10.0, -1, 120, 10}),
               std::invalid_argument);
}

}  // namespace
}  // namespace robotperf::control
