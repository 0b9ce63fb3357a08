// Torque offsets as the joint block of the parameter layout: the regressors against independent
// computations (the regressor without offsets plus identity columns, finite differences of the
// energy and momentum regressors along a trajectory), the base sets of the three methods against
// the rank of sampled regressors, and the names.
#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <utility>

#include "mindyn/base_parameters.hpp"
#include "mindyn/dynamics.hpp"
#include "mindyn/momentum.hpp"
#include "mindyn/slotine_li.hpp"
#include "test_util.hpp"

using namespace mindyn;

namespace {

ParameterLayout withOffsets(ParameterLayout layout) {
  layout.offset = true;
  return layout;
}

/// A planar arm of 3 joints whose rotor inertia and friction act on coupled motors.
Model motorSideArm() {
  Model m = planarArm(3);
  Eigen::MatrixXd T(3, 3);
  T << 2, 0, 0, 1, 3, 0, 0, -1, 4;
  m.transmission.format = "yaml";
  m.transmission.T = T;
  m.transmission.offset = Eigen::VectorXd::Zero(3);
  m.transmission.torque_constant = Eigen::VectorXd::Constant(3, NAN);
  for (int i = 0; i < 3; ++i) {
    m.transmission.motors.push_back(std::string(1, static_cast<char>('a' + i)));
    m.transmission.types.push_back("matrix");
  }
  m.validate();
  return m;
}

std::vector<std::pair<std::string, Model>> models() {
  auto out = test::chainsAndTrees();
  out.emplace_back("motor-side arm", motorSideArm());
  return out;
}

/// A random tree of n joints whose first joint is prismatic along the vertical, from the base,
/// and carries no other joint: its torque is M1 (ddq1 + g) + Ia1 ddq1 (+ friction), so that
/// M1 - Ia1 is the constant M1 g, collinear with the offset.
Model verticalPrismaticTree(std::mt19937& rng, int n) {
  Model m = test::randomTree(rng, n, true);
  m.joints[0].type = JointType::Prismatic;
  m.joints[0].pre.linear().setIdentity();
  m.joints[0].axis = Eigen::Vector3d::UnitZ();
  for (int k = 1; k < n; ++k)
    if (m.parents[k] == 0) m.parents[k] = -1;
  m.gravity = Eigen::Vector3d(0, 0, -9.81);
  m.name = "vertical-prismatic tree" + std::to_string(n);
  return m;
}

}  // namespace

TEST(Offsets, NamesAreTheJointBlockAfterTheLinks) {
  const Model model = loadYaml(test::robotFile("puma560"));
  const int n = model.nq();
  for (ParameterLayout layout : {ParameterLayout{false, false}, ParameterLayout{true, true}}) {
    const auto names = model.parameterNames(withOffsets(layout));
    const auto links = model.parameterNames(layout);
    ASSERT_EQ(static_cast<int>(names.size()), layout.size(n) + n);
    EXPECT_TRUE(std::equal(links.begin(), links.end(), names.begin()));
    for (int k = 0; k < n; ++k) {
      EXPECT_EQ(names[withOffsets(layout).offsetIndex(n, k)], "Off" + std::to_string(k + 1));
      EXPECT_EQ(model.parameters(withOffsets(layout))[layout.size(n) + k], 0.0);
    }
  }
  // never inferred from a size: 11 n is rotor inertia
  EXPECT_FALSE(ParameterLayout::fromSize(n, 11L * n).offset);
}

TEST(Offsets, RegressorIsTheRegressorWithoutThemAndIdentityColumns) {
  std::mt19937 rng(31);
  for (const auto& [name, model] : models()) {
    Data data(model);
    const int n = model.nq();
    for (ParameterLayout layout : {ParameterLayout{false, false}, ParameterLayout{true, true}}) {
      const ParameterLayout lo = withOffsets(layout);
      const int P = layout.size(n);
      ASSERT_EQ(lo.size(n), P + n);
      const Eigen::VectorXd q = test::random(rng, n, 2), dq = test::random(rng, n),
                            ddq = test::random(rng, n);
      Eigen::MatrixXd W(n, P), Wo(n, P + n);
      regressor(model, data, q, dq, ddq, layout, W);
      regressor(model, data, q, dq, ddq, lo, Wo);
      EXPECT_EQ(Wo.leftCols(P), W) << name;
      EXPECT_EQ(Wo.rightCols(n), Eigen::MatrixXd::Identity(n, n)) << name;
      // the torques: the offsets added to joint torques, on either drive side
      Eigen::VectorXd pi = test::random(rng, P + n), tau(n), tau0(n), ddq2(n), g(n), g0(n);
      pi.head(P) = model.parameters(layout);
      inverseDynamics(model, data, q, dq, ddq, pi, lo, tau);
      inverseDynamics(model, data, q, dq, ddq, pi.head(P), layout, tau0);
      EXPECT_LT((tau - tau0 - pi.tail(n)).norm(), 1e-12 * (1 + tau.norm())) << name;
      EXPECT_LT((Wo * pi - tau).norm(), 1e-10 * (1 + tau.norm())) << name;
      // not in the gravity torque; the forward dynamics inverts the inverse one
      gravityTorque(model, data, q, pi, lo, g);
      gravityTorque(model, data, q, pi.head(P), layout, g0);
      EXPECT_EQ(g, g0) << name;
      ASSERT_TRUE(forwardDynamics(model, data, q, dq, tau, pi, lo, ddq2)) << name;
      EXPECT_LT((ddq2 - ddq).norm(), 1e-8 * (1 + ddq.norm())) << name;
      // Slotine-Li regressor: the same identity columns (tau = Y pi at dqr = dq, ddqr = ddq)
      SlotineLiData sl(model, lo);
      Eigen::MatrixXd Y(n, P + n);
      slotineLiRegressor(model, data, sl, q, dq, dq, ddq, lo, Y);
      EXPECT_EQ(Y.rightCols(n), Eigen::MatrixXd::Identity(n, n)) << name;
      EXPECT_LT((Y * pi - tau).norm(), 1e-9 * (1 + tau.norm())) << name;
    }
  }
}

// Along q(t) = q0 + v t + a t^2 / 2: the power balance d/dt (w_K + w_P) pi = dq . (W pi) with
// the offsets' column of w_P their work, and the momentum form d/dt (W_p pi) + W_l pi = W pi, by
// central differences (rotor inertia, no friction: the balances hold without dissipation).
TEST(Offsets, EnergyAndMomentumColumnsByFiniteDifferences) {
  std::mt19937 rng(32);
  for (const auto& [name, model] : models()) {
    Data data(model);
    const int n = model.nq();
    const ParameterLayout lo = withOffsets(ParameterLayout{true, false});
    const int P = lo.size(n);
    Eigen::VectorXd pi = test::random(rng, P);
    pi.head(lo.linkSize(n)) = model.parameters(lo.links());
    const Eigen::VectorXd q0 = test::random(rng, n, 2), v = test::random(rng, n),
                          a = test::random(rng, n);
    auto at = [&](double t, Eigen::VectorXd& q, Eigen::VectorXd& dq) {
      q = q0 + v * t + 0.5 * a * t * t;
      dq = v + a * t;
    };
    Eigen::VectorXd q(n), dq(n), wK(P), wP(P);
    Eigen::MatrixXd W(n, P), Wp(n, P), Wl(n, P);
    auto energy = [&](double t) {
      at(t, q, dq);
      energyRegressors(model, data, q, dq, lo, wK, wP);
      return std::make_pair((wK + wP).dot(pi), wP.tail(n).eval());
    };
    auto momentum = [&](double t) {
      at(t, q, dq);
      momentumRegressors(model, data, q, dq, lo, Wp, Wl);
      return (Wp * pi).eval();
    };
    const double t = 0.3, h = 1e-5;
    const auto [Hp, offp] = energy(t + h);
    const auto [Hm, offm] = energy(t - h);
    const Eigen::VectorXd pp = momentum(t + h), pm = momentum(t - h);
    at(t, q, dq);
    regressor(model, data, q, dq, a, lo, W);
    const Eigen::VectorXd tau = W * pi;
    momentumRegressors(model, data, q, dq, lo, Wp, Wl);
    // the offsets' columns: work q_k in w_P (none in w_K), e_k in W_l, none in W_p
    energyRegressors(model, data, q, dq, lo, wK, wP);
    EXPECT_EQ(wP.tail(n), q) << name;
    EXPECT_EQ(wK.tail(n), Eigen::VectorXd::Zero(n)) << name;
    EXPECT_EQ(Wl.rightCols(n), Eigen::MatrixXd::Identity(n, n)) << name;
    EXPECT_EQ(Wp.rightCols(n), Eigen::MatrixXd::Zero(n, n)) << name;
    const double scale = 1 + std::abs(dq.dot(tau)) + tau.norm();
    EXPECT_LT(std::abs((Hp - Hm) / (2 * h) - dq.dot(tau)), 1e-6 * scale) << name;
    EXPECT_LT(((offp - offm) / (2 * h) - dq).norm(), 1e-8) << name;
    EXPECT_LT(((pp - pm) / (2 * h) + Wl * pi - tau).norm(), 1e-6 * scale) << name;
  }
}

// The base sets of the three methods with offsets: the same names and Y, their count the rank
// of the stacked regressor with its offset columns (SVD, independent of the methods), every
// offset a base parameter, last. Random trees whose first joint is a vertical prismatic one that
// carries nothing else: without rotor inertia its mass column M1 (ddq + g) is not constant (one
// base parameter more per offset); with it, M1 - Ia1 is the constant M1 g, and the known answer
// is that the mass regroups: IaR1 = Ia1 + M1, OffR1 = Off1 + g M1, one base parameter fewer.
TEST(Offsets, BaseSetsOfTheThreeMethodsOnTreesWithAVerticalPrismaticJoint) {
  std::mt19937 rng(33);
  for (int trial = 0; trial < 4; ++trial) {
    const Model model = verticalPrismaticTree(rng, 4 + trial % 3);
    const int n = model.nq();
    for (ParameterLayout layout : {ParameterLayout{false, false}, ParameterLayout{true, true}}) {
      const ParameterLayout lo = withOffsets(layout);
      const int P = lo.size(n);
      // the rank of the sampled regressor with offset columns
      const int states = 3 * P / n + 20;
      Eigen::MatrixXd Ws(states * n, P), W(n, P);
      Data data(model);
      for (int s = 0; s < states; ++s) {
        regressor(model, data, test::random(rng, n, 3), test::random(rng, n, 2),
                  test::random(rng, n, 3), lo, W);
        Ws.middleRows(s * n, n) = W;
      }
      const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(Ws).singularValues();
      const int rank = static_cast<int>((sv.array() > 1e-9 * sv[0]).count());
      BaseOptions links;
      links.layout = layout;
      const int without = computeBaseParameters(model, links).eom.size();
      EXPECT_EQ(rank, without + n - (layout.rotor ? 1 : 0)) << model.name;
      BaseOptions first;
      first.layout = lo;
      const BaseParameters proj = computeBaseParameters(model, first);
      for (BaseMethod method :
           {BaseMethod::Projection, BaseMethod::Recursive, BaseMethod::Numerical}) {
        BaseOptions o;
        o.layout = lo;
        o.method = method;
        const BaseParameters bp = computeBaseParameters(model, o);
        const int nb = bp.eom.size();
        EXPECT_EQ(nb, rank) << model.name << " method " << static_cast<int>(method);
        EXPECT_EQ(bp.eom.names, proj.eom.names) << model.name;
        // the known answer of the vertical prismatic joint
        const auto& names = bp.eom.names;
        const Eigen::MatrixXd Y(bp.eom.decision.Y);
        const int M1 = 9, Ia1 = layout.rotor ? lo.rotorIndex(0) : -1;
        const bool massKept = std::find(names.begin(), names.end(), "M1") != names.end() ||
                              std::find(names.begin(), names.end(), "MR1") != names.end();
        EXPECT_EQ(massKept, !layout.rotor) << model.name;
        EXPECT_NEAR(Y(nb - n, M1), layout.rotor ? 9.81 : 0.0, 1e-9) << model.name;
        EXPECT_EQ(names[nb - n], layout.rotor ? "OffR1" : "Off1") << model.name;
        if (layout.rotor) {
          const auto ia = std::find(names.begin(), names.end(), "IaR1");
          ASSERT_NE(ia, names.end()) << model.name;
          EXPECT_NEAR(Y(ia - names.begin(), M1), 1.0, 1e-9) << model.name;
          EXPECT_EQ(Y(ia - names.begin(), Ia1), 1.0) << model.name;
        }
        EXPECT_LT((Y - Eigen::MatrixXd(proj.eom.decision.Y)).cwiseAbs().maxCoeff(), 1e-9);
        ASSERT_EQ(bp.classical_names.size(), static_cast<size_t>(P));
        for (int k = 0; k < n; ++k) {
          EXPECT_EQ(bp.eom.decision.pivots[nb - n + k], lo.offsetIndex(n, k));
          if (k > 0)  // (joint 1's: below)
            EXPECT_EQ(bp.eom.names[nb - n + k], bp.classical_names[lo.offsetIndex(n, k)]);
        }
        // W = W_b Y, offset columns included; the energy sets hold no offset
        Eigen::MatrixXd Wb(n, nb);
        const Eigen::VectorXd q = test::random(rng, n, 3), dq = test::random(rng, n),
                              ddq = test::random(rng, n);
        baseRegressor(model, data, bp, q, dq, ddq, W, Wb);
        EXPECT_LT((Wb * Eigen::MatrixXd(bp.eom.decision.Y) - W).norm(), 1e-9 * W.norm());
        EXPECT_EQ(bp.lagrangian.decision.Y.cols(), P);
        for (int c : bp.lagrangian.decision.pivots) EXPECT_LT(c, lo.linkSize(n));
        const Eigen::VectorXd pi = test::random(rng, P);
        EXPECT_EQ(bp.values(pi).tail(n - 1), pi.tail(n - 1));
        EXPECT_EQ(bp.values(bp.embed(bp.values(pi))), bp.values(pi));
      }
    }
  }
}
