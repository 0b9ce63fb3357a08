// Shared helpers of the C++ tests.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "mindyn/description.hpp"
#include "mindyn/model.hpp"

namespace mindyn::test {

inline std::string robotFile(const std::string& name) {
  return std::string(MINDYN_ROBOT_DIR) + "/" + name + ".yaml";
}

inline Eigen::VectorXd random(std::mt19937& rng, int n, double scale = 1.0) {
  std::uniform_real_distribution<double> u(-scale, scale);
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) v[i] = u(rng);
  return v;
}

inline double relErr(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).norm() / std::max(1.0, b.norm());
}

/// The textbook closed form of planarArm(2, true, l, m): two uniform rods of radius `r` in a
/// vertical plane. Returns the joint torques; `gravity` receives the gravity part alone.
inline Eigen::Vector2d twoLinkTorque(const Eigen::VectorXd& q, const Eigen::VectorXd& dq,
                                     const Eigen::VectorXd& ddq, double l, double m, double r,
                                     double g, Eigen::Vector2d* gravity = nullptr) {
  const double lc = l / 2, I = m * (3 * r * r + l * l) / 12.0;
  const double c1 = std::cos(q[0]), c2 = std::cos(q[1]), s2 = std::sin(q[1]);
  const double c12 = std::cos(q[0] + q[1]);
  const double m11 = m * lc * lc + I + m * (l * l + lc * lc + 2 * l * lc * c2) + I;
  const double m12 = m * (lc * lc + l * lc * c2) + I;
  const double m22 = m * lc * lc + I;
  const double hh = m * l * lc * s2;
  Eigen::Vector2d gexp, tau;
  gexp << (m * lc + m * l) * g * c1 + m * lc * g * c12, m * lc * g * c12;
  tau[0] = m11 * ddq[0] + m12 * ddq[1] - hh * (2 * dq[0] * dq[1] + dq[1] * dq[1]) + gexp[0];
  tau[1] = m12 * ddq[0] + m22 * ddq[1] + hh * dq[0] * dq[0] + gexp[1];
  if (gravity) *gravity = gexp;
  return tau;
}

/// The bundled YAML robots.
inline std::vector<std::string> bundled() { return {"puma560", "puma560_3", "zcr07s", "stanford"}; }

/// The model with random positive rotor inertia and friction.
inline Model withExtras(Model m, std::mt19937& rng) {
  const int n = m.nq();
  m.rotor_inertia = random(rng, n).cwiseAbs();
  m.viscous = random(rng, n).cwiseAbs();
  m.coulomb = random(rng, n).cwiseAbs();
  return m;
}

}  // namespace mindyn::test
