// The Slotine-Li regressor against the ordinary regressor, the mass matrix and gravity torque,
// finite differences of the mass matrix (skew-symmetry of dA/dt - 2C, Christoffel symbols) and
// the base-parameter regrouping.
#include <gtest/gtest.h>

#include "mindyn/base_parameters.hpp"
#include "mindyn/slotine_li.hpp"
#include "test_util.hpp"

using namespace mindyn;
using mindyn::test::bundled;
using mindyn::test::random;
using mindyn::test::relErr;
using mindyn::test::withExtras;

namespace {

const ParameterLayout kLayouts[] = {{false, false}, {true, true}, {true, false}, {false, true}};

// dA/dq_k by central differences.
std::vector<Eigen::MatrixXd> massMatrixDerivatives(const Model& model, Data& data,
                                                   const Eigen::VectorXd& q,
                                                   const Eigen::VectorXd& pi,
                                                   ParameterLayout layout) {
  const int n = model.nq();
  const double h = 1e-6;
  std::vector<Eigen::MatrixXd> dA(n, Eigen::MatrixXd(n, n));
  Eigen::MatrixXd Ap(n, n), Am(n, n);
  for (int k = 0; k < n; ++k) {
    Eigen::VectorXd qp = q, qm = q;
    qp[k] += h;
    qm[k] -= h;
    massMatrix(model, data, qp, pi, layout, Ap);
    massMatrix(model, data, qm, pi, layout, Am);
    dA[k] = (Ap - Am) / (2 * h);
  }
  return dA;
}

}  // namespace

TEST(SlotineLi, EqualsTheRegressorWhenReferenceIsActualMotion) {
  std::mt19937 rng(11);
  for (const auto& [name, loaded] : test::chainsAndTrees()) {
    const Model model = loaded;
    Data data(model);
    const int n = model.nq();
    for (ParameterLayout layout : kLayouts) {
      SlotineLiData sl(model, layout);
      Eigen::MatrixXd W(n, layout.size(n)), Y(n, layout.size(n));
      for (int trial = 0; trial < 5; ++trial) {
        const Eigen::VectorXd q = random(rng, n, 3), dq = random(rng, n, 2),
                              ddq = random(rng, n, 5);
        regressor(model, data, q, dq, ddq, layout, W);
        slotineLiRegressor(model, data, sl, q, dq, dq, ddq, layout, Y);
        EXPECT_LT((W - Y).cwiseAbs().maxCoeff(), 1e-11 * std::max(1.0, W.cwiseAbs().maxCoeff()))
            << name;
      }
    }
  }
}

TEST(SlotineLi, RegressorIsMassMatrixCoriolisAndGravity) {
  std::mt19937 rng(12);
  for (const auto& [name, loaded] : test::chainsAndTrees()) {
    const Model model = withExtras(loaded, rng);
    Data data(model);
    const int n = model.nq();
    for (ParameterLayout layout : kLayouts) {
      SlotineLiData sl(model, layout);
      const int P = layout.size(n);
      Eigen::MatrixXd Y(n, P), A(n, n), C(n, n);
      Eigen::VectorXd c(n), tau(n), b(n), id(n);
      for (int trial = 0; trial < 5; ++trial) {
        const Eigen::VectorXd q = random(rng, n, 3), dq = random(rng, n, 2),
                              dqr = random(rng, n, 2), ddqr = random(rng, n, 5);
        const Eigen::VectorXd pi = random(rng, P);  // any vector: linearity is what is tested
        slotineLiRegressor(model, data, sl, q, dq, dqr, ddqr, layout, Y);
        massMatrix(model, data, q, pi, layout, A);
        coriolisMatrix(model, data, sl, q, dq, pi, layout, C);
        gravityTorque(model, data, q, pi, layout, c);
        Eigen::VectorXd expected = A * ddqr + C * dqr + c;
        if (layout.friction)
          for (int k = 0; k < n; ++k)
            expected[k] += pi[layout.viscousIndex(k)] * dq[k] +
                           pi[layout.coulombIndex(k)] * (dq[k] > 0 ? 1.0 : -1.0);
        EXPECT_LT(relErr(Y * pi, expected), 1e-11) << name;
        slotineLiTorque(model, data, sl, q, dq, dqr, ddqr, pi, layout, tau);
        EXPECT_LT(relErr(tau, expected), 1e-11) << name;
        // C(q, dq) dq is the velocity-product torque of Newton-Euler
        inverseDynamics(model, data, q, dq, sl.zeros, pi, layout, id);
        Eigen::VectorXd fr = Eigen::VectorXd::Zero(n);
        if (layout.friction)
          for (int k = 0; k < n; ++k)
            fr[k] = pi[layout.viscousIndex(k)] * dq[k] +
                    pi[layout.coulombIndex(k)] * (dq[k] > 0 ? 1.0 : -1.0);
        b = id - c - fr;
        EXPECT_LT(relErr(C * dq, b), 1e-11) << name;
      }
    }
  }
}

TEST(SlotineLi, MassMatrixDerivativeMinusTwoCoriolisIsSkewSymmetric) {
  std::mt19937 rng(13);
  for (const auto& [name, loaded] : test::chainsAndTrees()) {
    const Model model = withExtras(loaded, rng);
    Data data(model);
    const int n = model.nq();
    const ParameterLayout layout{true, false};
    SlotineLiData sl(model, layout);
    const Eigen::VectorXd pi = model.parameters(layout);
    Eigen::MatrixXd C(n, n);
    for (int trial = 0; trial < 5; ++trial) {
      const Eigen::VectorXd q = random(rng, n, 3), dq = random(rng, n, 2);
      const auto dA = massMatrixDerivatives(model, data, q, pi, layout);
      Eigen::MatrixXd Adot = Eigen::MatrixXd::Zero(n, n);
      for (int k = 0; k < n; ++k) Adot += dA[k] * dq[k];
      coriolisMatrix(model, data, sl, q, dq, pi, layout, C);
      const Eigen::MatrixXd N = Adot - 2 * C;
      const double scale = std::max(1.0, Adot.norm());
      EXPECT_LT((N + N.transpose()).norm() / scale, 1e-8) << name;
      // Not trivially skew: the Coriolis matrix itself is not.
      EXPECT_GT((C + C.transpose()).norm(), 1e-3 * C.norm()) << name;
    }
  }
}

TEST(SlotineLi, CoriolisMatrixIsTheChristoffelOne) {
  std::mt19937 rng(14);
  for (const auto& [name, loaded] : test::chainsAndTrees()) {
    const Model model = loaded;
    Data data(model);
    const int n = model.nq();
    SlotineLiData sl(model);
    const Eigen::VectorXd pi = model.parameters();
    Eigen::MatrixXd C(n, n);
    for (int trial = 0; trial < 3; ++trial) {
      const Eigen::VectorXd q = random(rng, n, 3), dq = random(rng, n, 2);
      const auto dA = massMatrixDerivatives(model, data, q, pi, {});
      Eigen::MatrixXd Cc = Eigen::MatrixXd::Zero(n, n);
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
          for (int k = 0; k < n; ++k)
            Cc(i, j) += 0.5 * (dA[k](i, j) + dA[j](i, k) - dA[i](j, k)) * dq[k];
      coriolisMatrix(model, data, sl, q, dq, pi, {}, C);
      EXPECT_LT((C - Cc).norm() / std::max(1.0, Cc.norm()), 1e-8) << name;
    }
  }
}

TEST(SlotineLi, BaseRegressorReproducesTheClassicalOne) {
  std::mt19937 rng(15);
  for (const auto& name : bundled()) {
    const Model model = loadYaml(test::robotFile(name));
    Data data(model);
    const int n = model.nq();
    for (ParameterLayout layout : {ParameterLayout{false, false}, ParameterLayout{true, true}}) {
      BaseOptions options;
      options.layout = layout;
      const BaseParameters bp = computeBaseParameters(model, options);
      SlotineLiData sl(model, layout);
      const int P = layout.size(n), nb = bp.eom.size();
      Eigen::MatrixXd Y(n, P), Yb(n, nb), Wb(n, nb), W(n, P);
      for (int trial = 0; trial < 5; ++trial) {
        const Eigen::VectorXd q = random(rng, n, 3), dq = random(rng, n, 2),
                              dqr = random(rng, n, 2), ddqr = random(rng, n, 5);
        const Eigen::VectorXd pi = random(rng, P);
        slotineLiRegressor(model, data, sl, q, dq, dqr, ddqr, layout, Y);
        slotineLiBaseRegressor(model, data, sl, bp, q, dq, dqr, ddqr, Yb);
        EXPECT_LT(relErr(Yb * bp.values(pi), Y * pi), 1e-9) << name;
        slotineLiBaseRegressor(model, data, sl, bp, q, dq, dq, ddqr, Yb);
        baseRegressor(model, data, bp, q, dq, ddqr, W, Wb);
        EXPECT_LT((Yb - Wb).cwiseAbs().maxCoeff(), 1e-11 * std::max(1.0, Wb.cwiseAbs().maxCoeff()))
            << name;
      }
    }
  }
}
