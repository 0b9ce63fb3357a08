// Reference regressors of a fixed-base tree assembled from serial chains: a link's kinetic and
// potential energies, and the torques its parameters cause, depend only on the joints of its
// root path, so they are those of the last link of the serial chain made of that path, computed
// by the serial algorithms (checked against Pinocchio and closed forms elsewhere).
#pragma once

#include <Eigen/Core>
#include <Eigen/SVD>
#include <random>
#include <string>
#include <vector>

#include "mindyn/data.hpp"
#include "mindyn/dynamics.hpp"
#include "mindyn/model.hpp"
#include "test_util.hpp"

namespace mindyn::test {

/// The root path of joint k (tree indices, from the base) and the serial chain made of it.
struct PathChain {
  std::vector<int> joints;
  Model model;
};

inline PathChain pathChain(const Model& tree, int k) {
  PathChain p;
  for (int j = k; j >= 0; j = tree.parent(j)) p.joints.insert(p.joints.begin(), j);
  Model& m = p.model;
  const int len = static_cast<int>(p.joints.size());
  m.name = tree.name + "_path" + std::to_string(k + 1);
  m.convention = "generated";
  m.gravity = tree.gravity;
  m.link_names.push_back(tree.link_names[0]);
  m.inertial.resize(10 * len);
  m.rotor_inertia.resize(len);
  m.viscous.resize(len);
  m.coulomb.resize(len);
  for (int i = 0; i < len; ++i) {
    const int j = p.joints[static_cast<size_t>(i)];
    m.joints.push_back(tree.joints[static_cast<size_t>(j)]);
    m.link_names.push_back(tree.link_names[static_cast<size_t>(j + 1)]);
    m.inertial.segment<10>(10 * i) = tree.inertial.segment<10>(10 * j);
    m.rotor_inertia[i] = tree.rotor_inertia[j];
    m.viscous[i] = tree.viscous[j];
    m.coulomb[i] = tree.coulomb[j];
  }
  m.validate();
  return p;
}

/// The entries of x (one per tree joint) on a path's joints.
inline Eigen::VectorXd along(const std::vector<int>& joints, const Eigen::VectorXd& x) {
  Eigen::VectorXd y(static_cast<long>(joints.size()));
  for (size_t i = 0; i < joints.size(); ++i) y[static_cast<long>(i)] = x[joints[i]];
  return y;
}

/// A tree's n x P regressor-like matrix assembled from the serial chains of its paths: the
/// parameters of link k (and its joint terms) act on the joints of its root path exactly as on
/// the last link of that path's chain, and on no other joint. `chain(model, joints)` returns the
/// chain's matrix (len x layout.size(len)) for the path's chain and the tree's joint indices.
template <class ChainMatrix>
Eigen::MatrixXd assembleByPaths(const Model& tree, ParameterLayout layout, ChainMatrix chain) {
  const int n = tree.nq(), L = layout.perLink();
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(n, layout.size(n));
  for (int k = 0; k < n; ++k) {
    const PathChain p = pathChain(tree, k);
    const int len = p.model.nq();
    const Eigen::MatrixXd Wp = chain(p.model, p.joints);
    for (int i = 0; i < len; ++i)
      W.block(p.joints[static_cast<size_t>(i)], k * L, 1, L) = Wp.block(i, (len - 1) * L, 1, L);
  }
  return W;
}

/// Trees for the tests: random ones of 3 to 8 joints (random parents: mostly shallow), and deeper
/// shapes with random geometry (a trunk forking into two arms, three branches from one joint,
/// forks at several depths), each with generic and with special geometry (see randomChain).
/// The name says which.
inline std::vector<Model> testTrees(std::mt19937& rng) {
  std::vector<Model> out;
  auto name = [](Model& m, bool special) {
    m.name = (special ? "special tree, parents" : "tree, parents");
    for (int k = 0; k < m.nq(); ++k) m.name += " " + std::to_string(m.parent(k));
  };
  for (int n = 3; n <= 8; ++n)
    for (bool special : {false, true}) {
      out.push_back(randomChain(rng, n, true, special, true));
      name(out.back(), special);
    }
  const std::vector<std::vector<int>> shapes = {
      {-1, 0, 1, 2, 1, 4, 5}, {-1, 0, 0, 0, 1, 2, 3}, {-1, 0, 1, 2, 3, 2, 1}};
  for (const auto& parents : shapes)
    for (bool special : {false, true}) {
      out.push_back(randomChain(rng, static_cast<int>(parents.size()), true, special));
      out.back().parents = parents;
      name(out.back(), special);
    }
  // Baxter's shape, 19 joints (more than a serial chain's projection handles): a head joint and
  // two 7-joint arms on the base, two finger joints on each wrist; special geometry (generic
  // 7-joint arms take a tenth of a second each).
  out.push_back(randomChain(rng, 19, true, true));
  out.back().parents = {-1, -1, 1, 2, 3, 4, 5, 6, 7, 7, -1, 10, 11, 12, 13, 14, 15, 16, 16};
  name(out.back(), true);
  return out;
}

/// The tree's Lagrangian regressor w_K - w_P, or with `total` the total-energy one w_K + w_P.
inline Eigen::VectorXd pathEnergyRegressor(const Model& tree, const Eigen::VectorXd& q,
                                           const Eigen::VectorXd& dq, ParameterLayout layout,
                                           bool total = false) {
  const int n = tree.nq(), L = layout.perLink();
  Eigen::VectorXd w = Eigen::VectorXd::Zero(layout.size(n));
  for (int k = 0; k < n; ++k) {
    const PathChain p = pathChain(tree, k);
    const int len = p.model.nq();
    Eigen::VectorXd wK(layout.size(len)), wP(layout.size(len));
    Data data(p.model);
    energyRegressors(p.model, data, along(p.joints, q), along(p.joints, dq), layout, wK, wP);
    if (total) wP = -wP;
    w.segment(k * L, L) = (wK - wP).segment((len - 1) * L, L);
  }
  return w;
}

/// The tree's regressor W (n x P): tau = W pi.
inline Eigen::MatrixXd pathRegressor(const Model& tree, const Eigen::VectorXd& q,
                                     const Eigen::VectorXd& dq, const Eigen::VectorXd& ddq,
                                     ParameterLayout layout) {
  return assembleByPaths(tree, layout, [&](const Model& chain, const std::vector<int>& joints) {
    Data data(chain);
    Eigen::MatrixXd Wp(chain.nq(), layout.size(chain.nq()));
    regressor(chain, data, along(joints, q), along(joints, dq), along(joints, ddq), layout, Wp);
    return Wp;
  });
}

/// The rank of the tree's regressor sampled at `states` random states, or with `energy` of its
/// Lagrangian regressor (one row per state): columns scaled to unit norm, singular values above
/// 1e-9 of the largest. Counts independent of the methods.
inline int sampledRank(const Model& tree, ParameterLayout layout, int states, std::mt19937& rng,
                       bool energy = false) {
  const int n = tree.nq(), P = layout.size(n), rows = energy ? 1 : n;
  Eigen::MatrixXd A(static_cast<long>(states) * rows, P);
  for (int s = 0; s < states; ++s) {
    const Eigen::VectorXd q = random(rng, n, 3.0), dq = random(rng, n, 2.0);
    if (energy)
      A.row(s) = pathEnergyRegressor(tree, q, dq, layout).transpose();
    else
      A.middleRows(static_cast<long>(s) * n, n) =
          pathRegressor(tree, q, dq, random(rng, n, 2.0), layout);
  }
  // Columns that special geometry makes zero hold rounding noise (about 1e-16 of the largest):
  // zero below 1e-11 of the largest, so that the scaling does not blow the noise up.
  const double largest = A.colwise().norm().maxCoeff();
  for (int c = 0; c < P; ++c) {
    const double norm = A.col(c).norm();
    if (norm > 1e-11 * largest)
      A.col(c) /= norm;
    else
      A.col(c).setZero();
  }
  Eigen::BDCSVD<Eigen::MatrixXd> svd(A);
  const Eigen::VectorXd& sv = svd.singularValues();
  int rank = 0;
  for (int i = 0; i < sv.size(); ++i)
    if (sv[i] > 1e-9 * sv[0]) ++rank;
  return rank;
}

}  // namespace mindyn::test
