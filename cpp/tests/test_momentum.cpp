// The integral-model regressors checked against independent code paths: the kinetic energy by
// central finite differences (dK/dq), the mass matrix (p = A dq) and the Newton-Euler inverse
// dynamics with a numerical time derivative of p (tau = dp/dt - dL/dq + friction).
#include <gtest/gtest.h>

#include <cmath>
#include <utility>

#include "mindyn/dynamics.hpp"
#include "mindyn/momentum.hpp"
#include "mindyn/urdf.hpp"
#include "test_util.hpp"

using namespace mindyn;
using mindyn::test::random;
using mindyn::test::relErr;

namespace {

std::vector<std::pair<std::string, Model>> robots() {
  std::mt19937 rng(11);
  std::vector<std::pair<std::string, Model>> out;
  for (const auto& [name, model] : test::chainsAndTrees())
    out.emplace_back(name, test::withExtras(model, rng));
  const std::string dir = MINDYN_ROBOT_DATA_DIR;
  if (dir.empty()) {
    ADD_FAILURE() << "MINDYN_ROBOT_DATA_DIR is not set";
    return out;
  }
  out.emplace_back(
      "ur5", test::withExtras(loadUrdf(dir + "/ur_description/urdf/ur5_robot.urdf", "tool0"), rng));
  out.emplace_back(
      "panda",
      test::withExtras(loadUrdf(dir + "/panda_description/urdf/panda.urdf", "panda_link8"), rng));
  return out;
}

const ParameterLayout kLayouts[] = {{false, false}, {true, true}};

}  // namespace

TEST(Momentum, MomentumIsMassMatrixTimesVelocity) {
  std::mt19937 rng(1);
  for (const auto& [name, model] : robots()) {
    Data data(model);
    const int n = model.nq();
    for (ParameterLayout layout : kLayouts) {
      const int P = layout.size(n);
      Eigen::MatrixXd Wp(n, P), Wl(n, P), M(n, n);
      const Eigen::VectorXd pi = model.parameters(layout);
      for (int trial = 0; trial < 5; ++trial) {
        const Eigen::VectorXd q = random(rng, n, 3), dq = random(rng, n, 2);
        momentumRegressors(model, data, q, dq, layout, Wp, Wl);
        massMatrix(model, data, q, pi, layout, M);
        EXPECT_LT(relErr(Wp * pi, M * dq), 1e-12) << name;
        if (layout.friction)
          for (int k = 0; k < n; ++k) {
            EXPECT_EQ(Wp.col(layout.viscousIndex(k)).norm(), 0.0);
            EXPECT_EQ(Wl.col(layout.coulombIndex(k)).norm(), 0.0);
          }
      }
    }
  }
}

TEST(Momentum, LagrangianGradientMatchesFiniteDifferences) {
  // -dL/dq = -dK/dq + dP/dq, both energies evaluated by their own code path; physically
  // meaningless parameters on purpose (everything is linear in them). Central differences with
  // step 1e-5: truncation ~1e-10 times third derivatives of order 10, rounding ~1e-16 * K / 1e-5;
  // 1e-7 relative leaves a margin of 100 over both.
  std::mt19937 rng(2);
  const double h = 1e-5;
  for (const auto& [name, model] : robots()) {
    Data data(model);
    const int n = model.nq();
    for (ParameterLayout layout : kLayouts) {
      const int P = layout.size(n);
      Eigen::MatrixXd Wp(n, P), Wl(n, P);
      for (int trial = 0; trial < 5; ++trial) {
        const Eigen::VectorXd q = random(rng, n, 3), dq = random(rng, n, 2), pi = random(rng, P);
        momentumRegressors(model, data, q, dq, layout, Wp, Wl);
        Eigen::VectorXd fd(n);
        for (int j = 0; j < n; ++j) {
          Eigen::VectorXd qp = q, qm = q;
          qp[j] += h;
          qm[j] -= h;
          const double Lp = kineticEnergy(model, data, qp, dq, pi, layout) -
                            potentialEnergy(model, data, qp, pi, layout);
          const double Lm = kineticEnergy(model, data, qm, dq, pi, layout) -
                            potentialEnergy(model, data, qm, pi, layout);
          fd[j] = -(Lp - Lm) / (2 * h);
        }
        EXPECT_LT(relErr(Wl * pi, fd), 1e-7)
            << name << " " << (Wl * pi).transpose() << " vs " << fd.transpose();
      }
    }
  }
}

TEST(Momentum, EquationsOfMotionInMomentumForm) {
  // Along q(t) = q0 + a sin(w t) + b cos(2 w t): tau(t) - friction = dp/dt - dL/dq, dp/dt by
  // a fourth-order central difference with step 1e-3 s (error ~1e-12 * fifth derivatives of
  // order 1e3 for w = 2 rad/s ... well below the 1e-7 relative bound).
  std::mt19937 rng(3);
  const double w = 2.0, h = 1e-3;
  for (const auto& [name, model] : robots()) {
    Data data(model);
    const int n = model.nq();
    const ParameterLayout layout{true, true};
    const int P = layout.size(n);
    const Eigen::VectorXd pi = model.parameters(layout);
    const Eigen::VectorXd q0 = random(rng, n, 1), a = random(rng, n, 1), b = random(rng, n, 1);
    auto state = [&](double t, Eigen::VectorXd& q, Eigen::VectorXd& dq, Eigen::VectorXd& ddq) {
      q = q0 + a * std::sin(w * t) + b * std::cos(2 * w * t);
      dq = a * w * std::cos(w * t) - b * 2 * w * std::sin(2 * w * t);
      ddq = -a * w * w * std::sin(w * t) - b * 4 * w * w * std::cos(2 * w * t);
    };
    Eigen::MatrixXd Wp(n, P), Wl(n, P);
    Eigen::VectorXd q(n), dq(n), ddq(n), tau(n);
    auto momentum = [&](double t) {
      state(t, q, dq, ddq);
      momentumRegressors(model, data, q, dq, layout, Wp, Wl);
      return Eigen::VectorXd(Wp * pi);
    };
    for (double t : {0.1, 0.7, 1.9}) {
      const Eigen::VectorXd dp =
          (-momentum(t + 2 * h) + 8 * momentum(t + h) - 8 * momentum(t - h) + momentum(t - 2 * h)) /
          (12 * h);
      state(t, q, dq, ddq);
      momentumRegressors(model, data, q, dq, layout, Wp, Wl);
      inverseDynamics(model, data, q, dq, ddq, pi, layout, tau);
      for (int k = 0; k < n; ++k)
        tau[k] -= pi[layout.viscousIndex(k)] * dq[k] +
                  pi[layout.coulombIndex(k)] * (dq[k] > 0 ? 1.0 : (dq[k] < 0 ? -1.0 : 0.0));
      EXPECT_LT(relErr(dp + Wl * pi, tau), 1e-7) << name << " t=" << t;
    }
  }
}

TEST(Momentum, BaseVersionsAreThePivotColumns) {
  for (const char* name : {"puma560", "stanford"}) {
    const Model model = loadYaml(test::robotFile(name));
    BaseOptions options;
    options.layout = {true, true};
    const BaseParameters base = computeBaseParameters(model, options);
    Data data(model);
    const int n = model.nq(), P = base.layout.size(n), nb = base.eom.size();
    std::mt19937 rng(4);
    const Eigen::VectorXd q = random(rng, n, 3), dq = random(rng, n, 2);
    Eigen::MatrixXd Wp(n, P), Wl(n, P), Wpb(n, nb), Wlb(n, nb), Wp2(n, P), Wl2(n, P);
    baseMomentumRegressors(model, data, base, q, dq, Wp, Wl, Wpb, Wlb);
    // p and -dL/dq of the model's parameters through the base set equal the classical ones.
    const Eigen::VectorXd pi = model.parameters(base.layout), pb = base.values(pi);
    momentumRegressors(model, data, q, dq, base.layout, Wp2, Wl2);
    EXPECT_LT(relErr(Wpb * pb, Wp2 * pi), 1e-10) << name;
    EXPECT_LT(relErr(Wlb * pb, Wl2 * pi), 1e-10) << name;
  }
}
