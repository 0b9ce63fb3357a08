// Shared helpers of the C++ tests.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdlib>
#include <random>
#include <string>
#include <utility>
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

inline Eigen::Vector3d randomUnit(std::mt19937& rng) { return random(rng, 3).normalized(); }

/// A chain (or, with `tree`, a tree) with joint origins, axes and link frames drawn at random; with
/// `special`, each joint axis is, at random, parallel or perpendicular to its parent's or general,
/// and each origin rotation a multiple of pi/2 or general, so that the regrouping rules of every
/// kind occur. With `tree`, each joint's parent is drawn among the base and the joints before it.
/// The inertial values are random numbers (not physically consistent).
inline Model randomChain(std::mt19937& rng, int n, bool prismatic, bool special,
                         bool tree = false) {
  Model m;
  m.name = (tree ? "randomtree" : "random") + std::to_string(n);
  m.convention = "generated";
  std::uniform_int_distribution<int> pick(0, 3);
  m.link_names.push_back("base");
  for (int k = 0; k < n; ++k) {
    Joint j;
    j.name = "j" + std::to_string(k + 1);
    j.type = prismatic && pick(rng) == 0 ? JointType::Prismatic : JointType::Revolute;
    if (special && pick(rng) != 0) {
      const double a = 1.5707963267948966 * pick(rng);
      j.pre.linear() =
          Eigen::AngleAxisd(a, Eigen::Vector3d::Unit(pick(rng) % 3)).toRotationMatrix();
      j.axis = Eigen::Vector3d::Unit(pick(rng) % 3);
    } else {
      j.pre.linear() =
          Eigen::AngleAxisd(1.3 * random(rng, 1)[0], randomUnit(rng)).toRotationMatrix();
      j.axis = randomUnit(rng);
    }
    j.pre.translation() = random(rng, 3, 0.4);
    if (pick(rng) == 0) {
      j.post.linear() = Eigen::AngleAxisd(0.7, randomUnit(rng)).toRotationMatrix();
      j.post.translation() = random(rng, 3, 0.1);
    }
    m.joints.push_back(j);
    m.link_names.push_back("l" + std::to_string(k + 1));
    if (tree) m.parents.push_back(std::uniform_int_distribution<int>(-1, k - 1)(rng));
  }
  m.inertial = random(rng, 10 * n);
  m.rotor_inertia = random(rng, n).cwiseAbs();
  m.viscous = random(rng, n).cwiseAbs();
  m.coulomb = random(rng, n).cwiseAbs();
  m.gravity = special ? Eigen::Vector3d(0, 0, -9.81) : Eigen::Vector3d(random(rng, 3, 9.81));
  return m;
}

/// A random tree (see randomChain) with physically consistent inertia (each link a box of random
/// size, mass and pose), random positive rotor inertia and friction, and gravity along -z.
inline Model randomTree(std::mt19937& rng, int n, bool special) {
  Model m = randomChain(rng, n, true, special, true);
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d size = random(rng, 3).cwiseAbs() * 0.3 + Eigen::Vector3d::Constant(0.05);
    const double mass = 1.0 + std::abs(random(rng, 1)[0]);
    const Eigen::Vector3d s2 = size.cwiseProduct(size);
    const Eigen::Vector3d moments =
        mass / 12 * Eigen::Vector3d(s2.y() + s2.z(), s2.x() + s2.z(), s2.x() + s2.y());
    const Eigen::Matrix3d R =
        Eigen::AngleAxisd(random(rng, 1, 3.0)[0], randomUnit(rng)).toRotationMatrix();
    m.inertial.segment<10>(10 * k) =
        inertialFromCom(mass, random(rng, 3, 0.2), R * moments.asDiagonal() * R.transpose());
  }
  m.gravity = Eigen::Vector3d(0, 0, -9.81);
  return m;
}

/// The bundled robots and three random trees: the models of the runtime dynamics tests.
inline std::vector<std::pair<std::string, Model>> chainsAndTrees() {
  std::vector<std::pair<std::string, Model>> out;
  for (const auto& name : bundled()) out.emplace_back(name, loadYaml(robotFile(name)));
  std::mt19937 rng(20261124);
  out.emplace_back("tree5 special", randomTree(rng, 5, true));
  out.emplace_back("tree7", randomTree(rng, 7, false));
  out.emplace_back("tree9 special", randomTree(rng, 9, true));
  for (int k = 5; k < 8; ++k)  // every draw branches
    if (out[static_cast<size_t>(k) - 1].second.isSerial()) std::abort();
  return out;
}

/// A tree with one joint of each kind, some with a DH link offset (post) to exercise it.
inline Model everyJointKind(const char* convention = "mdh") {
  const std::string yaml = std::string("name: every\nconvention: ") + convention + R"(
joints:
  - {name: fly, type: floating, alpha: 0.3, d: 0.1, theta: 0.2, r: 0.1,
     inertial: {mass: 3.0, com: [0.1, 0.0, -0.05], inertia: {xx: 0.1, yy: 0.2, zz: 0.15, xy: 0.01}}}
  - {name: ball, type: spherical, alpha: 1.1, d: 0.3, theta: -0.4, r: 0.2,
     inertial: {mass: 1.5, com: [0.0, 0.2, 0.1], inertia: {xx: 0.05, yy: 0.04, zz: 0.03, yz: 0.005}}}
  - {name: cardan, type: universal, alpha: -0.7, d: 0.2, theta: 0.9, r: -0.1,
     inertial: {mass: 1.0, com: [0.1, 0.1, 0.0], inertia: {xx: 0.02, yy: 0.03, zz: 0.025}}}
  - {name: cyl, type: cylindrical, parent: 1, alpha: 0.5, d: -0.2, theta: 0.1, r: 0.3,
     inertial: {mass: 0.8, com: [0.0, 0.0, 0.2], inertia: {xx: 0.02, yy: 0.02, zz: 0.01}}}
  - {name: slide, type: planar, parent: 4, alpha: 0.2, d: 0.1, theta: 1.2, r: 0.0,
     inertial: {mass: 0.6, com: [0.05, 0.0, 0.0], inertia: {xx: 0.01, yy: 0.012, zz: 0.011}}}
  - {name: hinge, type: revolute, parent: 2, alpha: 1.0, d: 0.25, theta: 0.0, r: 0.1,
     inertial: {mass: 0.7, com: [0.1, 0.0, 0.0], inertia: {xx: 0.01, yy: 0.01, zz: 0.01}}}
  - {name: rail, type: prismatic, parent: 6, alpha: -1.2, d: 0.1, theta: 0.3, r: 0.2,
     inertial: {mass: 0.4, com: [0.0, 0.1, 0.0], inertia: {xx: 0.005, yy: 0.004, zz: 0.006}}}
)";
  if (std::string(convention) == "mdh") return parseYaml(yaml);
  std::string dh = yaml;  // DH rows: a in place of r
  for (size_t at = dh.find(" r: "); at != std::string::npos; at = dh.find(" r: ", at))
    dh.replace(at, 4, " a: ");
  return parseYaml(dh);
}

}  // namespace mindyn::test
