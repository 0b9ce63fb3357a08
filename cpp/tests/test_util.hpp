// Shared helpers of the C++ tests.
#pragma once

#include <Eigen/Core>
#include <random>
#include <string>

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

}  // namespace mindyn::test
