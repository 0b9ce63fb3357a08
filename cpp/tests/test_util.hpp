// Shared helpers of the C++ tests.
#pragma once

#include <Eigen/Core>
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
