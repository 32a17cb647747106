#include "planning/time_parametrization.hpp"

#include <algorithm>
#include <cmath>

namespace qte::planning {
namespace {

// Trapezoidal profile of the path parameter s in [0, 1] with limits v, a (per unit of s).
struct Profile {
  double v, a, t_accel, t_total;
  Profile(double v_max, double a_max) : v(v_max), a(a_max) {
    if (v * v / a >= 1.0) {  // never reaches full speed: triangle
      t_accel = std::sqrt(1.0 / a);
      v = a * t_accel;
      t_total = 2 * t_accel;
    } else {
      t_accel = v / a;
      t_total = 1.0 / v + t_accel;
    }
  }
  double s(double t) const {
    if (t <= 0) return 0;
    if (t >= t_total) return 1;
    if (t < t_accel) return 0.5 * a * t * t;
    if (t > t_total - t_accel) return 1.0 - 0.5 * a * (t_total - t) * (t_total - t);
    return 0.5 * a * t_accel * t_accel + v * (t - t_accel);
  }
};

}  // namespace

TimedPath time_parametrize(const std::vector<robot::JointVector>& waypoints,
                           const robot::JointVector& max_velocity,
                           const robot::JointVector& max_acceleration, double sample_period_s) {
  TimedPath out;
  if (waypoints.empty()) return out;
  out.time_s.push_back(0);
  out.joint_positions.push_back(waypoints[0]);
  double t0 = 0;
  for (std::size_t i = 1; i < waypoints.size(); ++i) {
    const robot::JointVector delta = waypoints[i] - waypoints[i - 1];
    double v = 1e9, a = 1e9;  // in units of the segment (s per second)
    for (int k = 0; k < robot::kArmJoints; ++k) {
      if (std::abs(delta[k]) < 1e-12) continue;
      v = std::min(v, max_velocity[k] / std::abs(delta[k]));
      a = std::min(a, max_acceleration[k] / std::abs(delta[k]));
    }
    if (v >= 1e9) continue;  // a repeated waypoint
    const Profile profile(v, a);
    const int samples = std::max(1, static_cast<int>(std::ceil(profile.t_total / sample_period_s - 1e-9)));
    for (int k = 1; k <= samples; ++k) {
      const double t = std::min(profile.t_total, k * sample_period_s);
      out.time_s.push_back(t0 + t);
      out.joint_positions.push_back(waypoints[i - 1] + profile.s(t) * delta);
    }
    t0 += profile.t_total;
  }
  return out;
}

}  // namespace qte::planning
