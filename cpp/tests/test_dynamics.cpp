// Dynamics checked against closed forms, energy identities and internal consistency of
// independent code paths (Newton-Euler vs regressor vs energies vs mass matrix).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "mindyn/dynamics.hpp"
#include "test_util.hpp"
#include "tree_paths.hpp"

using namespace mindyn;
using mindyn::test::bundled;
using mindyn::test::random;
using mindyn::test::relErr;
using mindyn::test::withExtras;

namespace {}  // namespace

TEST(Dynamics, TwoLinkPlanarClosedForm) {
  // Vertical-plane two-link arm of uniform rods: the textbook closed form.
  const double l = 0.5, m = 2.0, r = 0.02, g = 9.81;
  Model model = planarArm(2, true, l, m);
  Data data(model);
  std::mt19937 rng(1);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::VectorXd q = random(rng, 2, M_PI), dq = random(rng, 2, 2), ddq = random(rng, 2, 3);
    const Eigen::Vector2d expected = test::twoLinkTorque(q, dq, ddq, l, m, r, g);
    Eigen::VectorXd tau(2);
    inverseDynamics(model, data, q, dq, ddq, model.parameters(), {}, tau);
    EXPECT_LT(relErr(tau, expected), 1e-12) << tau.transpose() << " vs " << expected.transpose();
  }
}

TEST(Dynamics, RegressorTimesParametersIsInverseDynamics) {
  std::mt19937 rng(2);
  for (const auto& [name, loaded] : test::chainsAndTrees()) {
    const Model model = withExtras(loaded, rng);
    Data data(model);
    const int n = model.nq();
    for (ParameterLayout layout : {ParameterLayout{false, false}, ParameterLayout{true, true},
                                   ParameterLayout{true, false}, ParameterLayout{false, true}}) {
      const int P = layout.size(n);
      Eigen::MatrixXd W(n, P);
      Eigen::VectorXd tau(n);
      for (int trial = 0; trial < 10; ++trial) {
        const Eigen::VectorXd q = random(rng, n, 3), dq = random(rng, n, 2),
                              ddq = random(rng, n, 5);
        const Eigen::VectorXd pi = random(rng, P);  // physically meaningless on purpose
        regressor(model, data, q, dq, ddq, layout, W);
        inverseDynamics(model, data, q, dq, ddq, pi, layout, tau);
        EXPECT_LT(relErr(W * pi, tau), 1e-12) << name;
      }
    }
  }
}

TEST(Dynamics, EnergyRegressorsAndKineticEnergyFromMassMatrix) {
  std::mt19937 rng(3);
  for (const auto& [name, loaded] : test::chainsAndTrees()) {
    const Model model = withExtras(loaded, rng);
    Data data(model);
    const int n = model.nq();
    const ParameterLayout layout{true, true};
    const Eigen::VectorXd pi = model.parameters(layout);
    Eigen::VectorXd wK(layout.size(n)), wP(layout.size(n));
    Eigen::MatrixXd M(n, n);
    for (int trial = 0; trial < 10; ++trial) {
      const Eigen::VectorXd q = random(rng, n, 3), dq = random(rng, n, 2);
      energyRegressors(model, data, q, dq, layout, wK, wP);
      const double K = kineticEnergy(model, data, q, dq, pi, layout);
      const double P = potentialEnergy(model, data, q, pi, layout);
      massMatrix(model, data, q, pi, layout, M);
      EXPECT_NEAR(wK.dot(pi), K, 1e-12 * std::max(1.0, std::abs(K))) << name;
      EXPECT_NEAR(wP.dot(pi), P, 1e-12 * std::max(1.0, std::abs(P))) << name;
      EXPECT_NEAR(0.5 * dq.dot(M * dq), K, 1e-11 * std::max(1.0, std::abs(K))) << name;
    }
  }
}

TEST(Dynamics, PotentialEnergyGradientIsGravityTorque) {
  std::mt19937 rng(4);
  for (const auto& [name, loaded] : test::chainsAndTrees()) {
    const Model model = loaded;
    Data data(model);
    const int n = model.nq();
    const Eigen::VectorXd pi = model.parameters();
    const Eigen::VectorXd q = random(rng, n, 2);
    Eigen::VectorXd g(n), fd(n);
    gravityTorque(model, data, q, pi, {}, g);
    const double h = 1e-6;
    for (int k = 0; k < n; ++k) {
      Eigen::VectorXd qp = q, qm = q;
      qp[k] += h;
      qm[k] -= h;
      fd[k] =
          (potentialEnergy(model, data, qp, pi, {}) - potentialEnergy(model, data, qm, pi, {})) /
          (2 * h);
    }
    EXPECT_LT(relErr(g, fd), 1e-7) << name << ": " << g.transpose() << " vs " << fd.transpose();
  }
}

TEST(Dynamics, PowerBalanceAlongATrajectory) {
  // dH/dt = dq^T tau for a frictionless robot, by central differences of H along
  // q(t) = q0 + dq0 t + ddq0 t^2 / 2.
  std::mt19937 rng(5);
  for (const auto& [name, loaded] : test::chainsAndTrees()) {
    Model model = withExtras(loaded, rng);
    Data data(model);
    const int n = model.nq();
    const ParameterLayout layout{true, false};
    const Eigen::VectorXd pi = model.parameters(layout);
    for (int trial = 0; trial < 5; ++trial) {
      const Eigen::VectorXd q0 = random(rng, n, 2), dq0 = random(rng, n, 1),
                            ddq0 = random(rng, n, 2);
      auto H = [&](double t) {
        const Eigen::VectorXd q = q0 + dq0 * t + 0.5 * ddq0 * t * t, dq = dq0 + ddq0 * t;
        return kineticEnergy(model, data, q, dq, pi, layout) +
               potentialEnergy(model, data, q, pi, layout);
      };
      const double h = 1e-5;
      const double dH = (H(h) - H(-h)) / (2 * h);
      Eigen::VectorXd tau(n);
      inverseDynamics(model, data, q0, dq0, ddq0, pi, layout, tau);
      EXPECT_NEAR(dH, dq0.dot(tau), 1e-6 * std::max(1.0, std::abs(dH))) << name;
    }
  }
}

TEST(Dynamics, MassMatrixSymmetricPositiveDefiniteAndForwardDynamicsInverts) {
  std::mt19937 rng(6);
  for (const auto& [name, loaded] : test::chainsAndTrees()) {
    const Model model = withExtras(loaded, rng);
    Data data(model);
    const int n = model.nq();
    const ParameterLayout layout{true, true};
    const Eigen::VectorXd pi = model.parameters(layout);
    Eigen::MatrixXd M(n, n);
    Eigen::VectorXd tau(n), ddq2(n);
    for (int trial = 0; trial < 10; ++trial) {
      const Eigen::VectorXd q = random(rng, n, 3), dq = random(rng, n, 2), ddq = random(rng, n, 5);
      massMatrix(model, data, q, pi, layout, M);
      EXPECT_LT((M - M.transpose()).norm(), 1e-14 * M.norm());
      EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(M).eigenvalues().minCoeff(), 0.0)
          << name;
      inverseDynamics(model, data, q, dq, ddq, pi, layout, tau);
      ASSERT_TRUE(forwardDynamics(model, data, q, dq, tau, pi, layout, ddq2));
      EXPECT_LT(relErr(ddq2, ddq), 1e-9) << name;
    }
  }
}

TEST(Dynamics, ForwardDynamicsReportsSingularInertia) {
  Model model = planarArm(2);
  Data data(model);
  const Eigen::VectorXd pi = Eigen::VectorXd::Zero(20);
  Eigen::VectorXd q = Eigen::VectorXd::Zero(2), ddq = Eigen::VectorXd::Constant(2, 7.0);
  EXPECT_FALSE(forwardDynamics(model, data, q, q, q, pi, {}, ddq));
  EXPECT_EQ(ddq[0], 7.0);
}

TEST(Dynamics, SizeChecksNameTheArgument) {
  const Model model = planarArm(3);
  try {
    checkSizes(model, {}, 3, 2, 3, 30);
    FAIL() << "expected an exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("dq has 2 entries"), std::string::npos) << e.what();
  }
  EXPECT_THROW(checkSizes(model, {true, false}, 3, 3, 3, 30), std::invalid_argument);
  EXPECT_NO_THROW(checkSizes(model, {true, false}, 3, 3, 3, 33));
}

TEST(Dynamics, TreeWithMasslessSideBranchesActsAsItsRootPath) {
  // Independent of the tree code: the serial chain of one root path, computed by the chain
  // algorithms, must give the torques of that path's joints when every other link of the tree
  // is massless (and the side joints' torques are then zero).
  std::mt19937 rng(7);
  for (int trial = 0; trial < 6; ++trial) {
    Model tree = test::randomTree(rng, 8, trial % 2 == 0);
    const int n = tree.nq();
    const test::PathChain pc = test::pathChain(tree, n - 1);  // the last joint's root path
    const std::vector<int>& path = pc.joints;
    const Model& chain = pc.model;
    const int m = chain.nq();
    for (int k = 0; k < n; ++k)
      if (std::find(path.begin(), path.end(), k) == path.end())
        tree.inertial.segment<10>(10 * k).setZero();
    Data dt(tree), dc(chain);
    const Eigen::VectorXd q = random(rng, n, 3), dq = random(rng, n, 2), ddq = random(rng, n, 5);
    Eigen::VectorXd tau(n), tauc(m);
    inverseDynamics(tree, dt, q, dq, ddq, tree.parameters(), {}, tau);
    inverseDynamics(chain, dc, test::along(path, q), test::along(path, dq), test::along(path, ddq),
                    chain.parameters(), {}, tauc);
    EXPECT_LT(relErr(test::along(path, tau), tauc), 1e-12) << "trial " << trial;
    for (int k = 0; k < n; ++k) {
      if (std::find(path.begin(), path.end(), k) == path.end()) {
        EXPECT_LT(std::abs(tau[k]), 1e-12 * tauc.norm()) << "side joint " << k;
      }
    }
  }
}
