// The generalised-momentum observer: its discrete update against the first-order recursion it
// stands for (r_k = a r_{k-1} + c D_k, D_k formed here from the momentum regressors and the
// Newton-Euler regressor directly), the gain check, and allocation freedom per step (malloc
// counter of this test program).
#include <gtest/gtest.h>

#include <cmath>

#include "malloc_counter.hpp"
#include "mindyn/base_parameters.hpp"
#include "mindyn/momentum.hpp"
#include "mindyn/momentum_observer.hpp"
#include "test_util.hpp"

using namespace mindyn;
using mindyn::test::Count;

namespace {

BaseParameters baseOf(const Model& model, ParameterLayout layout) {
  BaseOptions options;
  options.layout = layout;
  return computeBaseParameters(model, options);
}

}  // namespace

TEST(MomentumObserver, StepAllocatesNothing) {
  for (const auto& [name, model] : test::chainsAndTrees()) {
    const ParameterLayout layout{true, true};
    const BaseParameters base = baseOf(model, layout);
    const int n = model.nq();
    const Eigen::VectorXd values = base.values(model.parameters(layout));
    const double T = 0.001;
    MomentumObserver obs(model, base, values,
                         Eigen::VectorXd::Constant(n, MomentumObserver::defaultGain(T)), T,
                         Eigen::VectorXd::Constant(n, 0.1));
    std::mt19937 rng(31);
    const Eigen::VectorXd q = test::random(rng, n), dq = test::random(rng, n),
                          tau = test::random(rng, n);
    Eigen::VectorXd r(n);
    obs.reset(q, dq, tau);
    long seen;
    {
      Count c;
      for (int i = 0; i < 3; ++i) obs.step(q, dq, tau, r);
      seen = c.value();
    }
    EXPECT_EQ(seen, 0) << name;
    EXPECT_TRUE(r.allFinite()) << name;
  }
}

// With held torque: r_k = a r_{k-1} + c (p_k - p_{k-1} - T tau_{k-1} + T/2 (beta_k + beta_{k-1})),
// a = (1 - K T/2) / (1 + K T/2), c = K / (1 + K T/2); p and beta of the classical parameters
// (rotor, friction) plus the offsets, evaluated here without the base parameters.
TEST(MomentumObserver, IsTheFirstOrderRecursion) {
  for (const char* name : {"puma560", "zcr07s", "stanford"}) {
    const Model model = loadYaml(test::robotFile(name));
    const ParameterLayout layout{true, true};
    const BaseParameters base = baseOf(model, layout);
    const int n = model.nq(), P = layout.size(n);
    const Eigen::VectorXd pi = model.parameters(layout);
    std::mt19937 rng(7);
    const Eigen::VectorXd off = test::random(rng, n);
    Eigen::VectorXd K(n);
    for (int j = 0; j < n; ++j) K[j] = 50.0 * (j + 1);
    const double T = 0.002;
    for (bool held : {true, false}) {
      MomentumObserver obs(model, base, base.values(pi), K, T, off, held);
      Data data(model);
      Eigen::MatrixXd Wp(n, P), Wl(n, P), W(n, P);
      auto terms = [&](const Eigen::VectorXd& q, const Eigen::VectorXd& dq, Eigen::VectorXd& p,
                       Eigen::VectorXd& beta) {
        momentumRegressors(model, data, q, dq, layout, Wp, Wl);
        regressor(model, data, q, dq, Eigen::VectorXd::Zero(n), layout, W);
        p = Wp * pi;
        beta = Wl * pi + off;
        for (int j = 0; j < n; ++j)  // friction: the Newton-Euler regressor's friction columns
          beta[j] += W(j, layout.viscousIndex(j)) * pi[layout.viscousIndex(j)] +
                     W(j, layout.coulombIndex(j)) * pi[layout.coulombIndex(j)];
      };
      Eigen::VectorXd q = test::random(rng, n), dq = test::random(rng, n),
                      tau = test::random(rng, n, 5.0), p0, b0, p1, b1, r(n), expect(n);
      obs.reset(q, dq, tau);
      terms(q, dq, p0, b0);
      Eigen::VectorXd prev = Eigen::VectorXd::Zero(n);
      double worst = 0;
      for (int k = 1; k < 40; ++k) {
        const Eigen::VectorXd tau1 = test::random(rng, n, 5.0);
        q += T * dq;
        dq += test::random(rng, n, 0.05);
        obs.step(q, dq, tau1, r);
        terms(q, dq, p1, b1);
        for (int j = 0; j < n; ++j) {
          const double h = 0.5 * K[j] * T, a = (1 - h) / (1 + h), c = K[j] / (1 + h);
          const double torque = held ? T * tau[j] : 0.5 * T * (tau[j] + tau1[j]);
          expect[j] = a * prev[j] + c * (p1[j] - p0[j] - torque + 0.5 * T * (b1[j] + b0[j]));
        }
        worst = std::max(worst, (r - expect).cwiseAbs().maxCoeff() / (1 + expect.norm()));
        prev = r;
        p0 = p1;
        b0 = b1;
        tau = tau1;
      }
      EXPECT_LT(worst, 1e-10) << name << (held ? " held" : " sampled");
    }
  }
}

TEST(MomentumObserver, RefusesGainsOutOfRange) {
  const Model model = loadYaml(test::robotFile("puma560"));
  const BaseParameters base = baseOf(model, {});
  const Eigen::VectorXd v = base.values(model.parameters({}));
  const int n = model.nq();
  EXPECT_THROW(MomentumObserver(model, base, v, Eigen::VectorXd::Constant(n, 2000.0), 0.001),
               ModelError);  // K T = 2
  EXPECT_THROW(MomentumObserver(model, base, v, Eigen::VectorXd::Zero(n), 0.001), ModelError);
  EXPECT_THROW(MomentumObserver(model, base, v, Eigen::VectorXd::Constant(n - 1, 10.0), 0.001),
               ModelError);
  EXPECT_NO_THROW(MomentumObserver(model, base, v, Eigen::VectorXd::Constant(n, 1999.0), 0.001));
}
