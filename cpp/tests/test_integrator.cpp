// The closed-loop simulation's plant: RK4 of the forward dynamics with the torque held, against
// closed forms (a joint with inertia, viscous and Coulomb friction under a constant torque),
// its fourth order of convergence and energy conservation of a free two-link arm (allocation-free
// steps: test_realtime.cpp).
#include <gtest/gtest.h>

#include <cmath>

#include "mindyn/description.hpp"
#include "mindyn/dynamics.hpp"
#include "mindyn/integrator.hpp"
#include "test_util.hpp"

using namespace mindyn;

namespace {

// One joint in a horizontal plane (no gravity torque) with rotor inertia, viscous and Coulomb
// friction: J ddq + Fv dq + Fc sign(dq) = tau. For tau > Fc and dq0 > 0 the velocity stays
// positive and the motion is linear: dq(t) = a + (dq0 - a) e^(-r t), a = (tau - Fc) / Fv,
// r = Fv / J, q(t) = q0 + a t + (dq0 - a) (1 - e^(-r t)) / r.
struct OneJoint {
  Model model = planarArm(1, false);
  ParameterLayout layout{true, true};
  Eigen::VectorXd params;
  double J = 0, Fv = 0.8, Fc = 0.3, tau = 1.5, q0 = 0.2, dq0 = 0.1;

  OneJoint() {
    model.rotor_inertia[0] = 0.05;
    model.viscous[0] = Fv;
    model.coulomb[0] = Fc;
    params = model.parameters(layout);
    Data data(model);
    Eigen::MatrixXd A(1, 1);
    massMatrix(model, data, Eigen::VectorXd::Zero(1), params, layout, A);
    J = A(0, 0);
  }
  Eigen::Vector2d exact(double t) const {
    const double a = (tau - Fc) / Fv, r = Fv / J, e = std::exp(-r * t);
    return {q0 + a * t + (dq0 - a) * (1 - e) / r, a + (dq0 - a) * e};
  }
  // (q, dq) after T seconds of `periods` calls with `substeps` steps each
  Eigen::Vector2d run(double T, int periods, int substeps) const {
    Integrator integ(model, params, layout);
    Data data(model);
    Eigen::VectorXd q(1), dq(1), u(1);
    q << q0;
    dq << dq0;
    u << tau;
    for (int i = 0; i < periods; ++i)
      EXPECT_TRUE(integ.step(data, q, dq, u, T / periods, substeps));
    return {q[0], dq[0]};
  }
};

}  // namespace

TEST(Integrator, OneJointWithFrictionAgainstTheClosedForm) {
  const OneJoint s;
  ASSERT_GT(s.J, 0.05);  // the rod's inertia about the joint plus the rotor's
  const double T = 2.0;
  const Eigen::Vector2d got = s.run(T, 500, 4), want = s.exact(T);
  // h = 1 ms, r = Fv / J ~ 10 /s: the RK4 error is ~ T (h r)^4 / 120 ~ 1e-10 of the state;
  // 1e-9 leaves a margin of ten
  EXPECT_NEAR(got[0], want[0], 1e-9 * std::abs(want[0]));
  EXPECT_NEAR(got[1], want[1], 1e-9 * std::abs(want[1]));
}

TEST(Integrator, FourthOrderConvergence) {
  const OneJoint s;
  const double T = 1.0;
  const Eigen::Vector2d want = s.exact(T);
  double previous = 0;
  for (int steps : {8, 16, 32, 64}) {  // h = T / steps, one period of `steps` substeps
    const double err = (s.run(T, 1, steps) - want).norm();
    ASSERT_GT(err, 1e-13);  // well above round-off, so that the ratio measures the order
    if (previous > 0) {
      // halving h divides the error of a fourth-order method by 2^4 = 16 asymptotically (the
      // ratio is 19.4 at the coarsest step here: higher-order terms); a third- or fifth-order
      // method would give 8 or 32
      EXPECT_GT(previous / err, 13.0) << steps;
      EXPECT_LT(previous / err, 21.0) << steps;
    }
    previous = err;
  }
}

TEST(Integrator, SubstepsAndPeriodsAreTheSameSteps) {
  // 4 periods of 5 substeps and 20 periods of one step take the same 20 steps of h = T / 20
  const OneJoint s;
  const Eigen::Vector2d a = s.run(0.5, 4, 5), b = s.run(0.5, 20, 1);
  EXPECT_NEAR(a[0], b[0], 1e-14);
  EXPECT_NEAR(a[1], b[1], 1e-14);
}

TEST(Integrator, SmoothedCoulombFriction) {
  OneJoint s;
  const double eps = 0.05;
  Integrator integ(s.model, s.params, s.layout, eps);
  Data data(s.model);
  Eigen::VectorXd q(1), dq(1), u(1), ddq(1);
  q << 0.3;
  u << 0.2;
  for (double v : {-0.2, -0.01, 0.0, 0.03, 0.5}) {
    dq << v;
    ASSERT_TRUE(integ.acceleration(data, q, dq, u, ddq));
    const double want = (u[0] - s.Fv * v - s.Fc * std::tanh(v / eps)) / s.J;
    EXPECT_NEAR(ddq[0], want, 1e-12 * std::max(1.0, std::abs(want))) << v;
  }
  Integrator sharp(s.model, s.params, s.layout);
  dq << 0.0;  // sign(0) = 0: no Coulomb torque at rest
  ASSERT_TRUE(sharp.acceleration(data, q, dq, u, ddq));
  EXPECT_NEAR(ddq[0], u[0] / s.J, 1e-12);
}

TEST(Integrator, FreeTwoLinkArmConvergesAndConservesEnergy) {
  // A vertical two-link arm without friction and torque (nonlinear): the state error against a
  // run with a 40 times smaller step falls with the step as a fourth-order method's, and the
  // total energy
  // (computed from the kinetic and potential energies, not from the integrated accelerations)
  // stays constant to within the integration error.
  const Model model = planarArm(2, true);
  const ParameterLayout layout{};
  const Eigen::VectorXd p = model.parameters(layout);
  Data data(model);
  Integrator integ(model, p, layout);
  const Eigen::Vector2d q0(0.4, -0.7), dq0(1.0, -0.5);
  auto run = [&](int steps) {
    Eigen::VectorXd q = q0, dq = dq0;
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(2);
    EXPECT_TRUE(integ.step(data, q, dq, zero, 0.3, steps));
    Eigen::VectorXd x(4);
    x << q, dq;
    return x;
  };
  auto energy = [&](const Eigen::VectorXd& x) {
    return kineticEnergy(model, data, x.head(2), x.tail(2), p, layout) +
           potentialEnergy(model, data, x.head(2), p, layout);
  };
  const Eigen::VectorXd fine = run(6400);
  Eigen::VectorXd x0(4);
  x0 << q0, dq0;
  const double e0 = energy(x0);
  // 0.3 s from (q0, dq0): errors measured 3.6e-4, 2.0e-6, 5.5e-7, 5.4e-8, 4.0e-9 for 10 .. 160
  // steps (the order shows over several halvings; the components' errors partly cancel, so a
  // single ratio is not 16 here as it is in the linear case above)
  double previous = 0;
  for (int steps : {10, 20, 40, 80, 160}) {
    const Eigen::VectorXd x = run(steps);
    const double err = (x - fine).norm();
    if (previous > 0) {
      EXPECT_LT(err, previous) << steps;
    }
    previous = err;
  }
  const Eigen::VectorXd x40 = run(40), x160 = run(160);
  // two halvings: 16^2 = 256 for a fourth-order method, 64 for a third-order one
  EXPECT_GT((x40 - fine).norm() / (x160 - fine).norm(), 64.0);
  EXPECT_LT((x160 - fine).norm(), 1e-8);
  EXPECT_LT(std::abs(energy(x160) - e0), 1e-8);  // J
}

TEST(Integrator, BadSetupThrows) {
  const Model model = planarArm(2, true);
  const ParameterLayout layout{true, false};
  EXPECT_THROW(Integrator(model, Eigen::VectorXd::Zero(3), layout), std::invalid_argument);
  const Eigen::VectorXd p = model.parameters(layout);
  EXPECT_THROW(Integrator(model, p, layout, -1.0), std::invalid_argument);
  EXPECT_THROW(Integrator(model, p, layout, NAN), std::invalid_argument);
  Eigen::VectorXd bad = p;
  bad[3] = INFINITY;
  EXPECT_THROW(Integrator(model, bad, layout), std::invalid_argument);
  Integrator integ(model, p, layout);
  Data data(model);
  Eigen::VectorXd q = Eigen::VectorXd::Zero(2), dq = q, tau = q;
  EXPECT_FALSE(integ.step(data, q, dq, tau, 0.0, 1));
  EXPECT_FALSE(integ.step(data, q, dq, tau, 0.1, 0));
}
