// The per-call paths allocate nothing: every heap allocation made through malloc, calloc,
// realloc or operator new (which goes through malloc in libstdc++) is counted while a guard is
// active.
#include <gtest/gtest.h>

#include <cmath>

#include "malloc_counter.hpp"
#include "mindyn/base_parameters.hpp"
#include "mindyn/dynamics.hpp"
#include "mindyn/ik.hpp"
#include "mindyn/integrator.hpp"
#include "mindyn/momentum.hpp"
#include "mindyn/multibody.hpp"
#include "mindyn/slotine_li.hpp"
#include "test_util.hpp"

using namespace mindyn;
using mindyn::test::Count;

TEST(Realtime, TheCounterSeesAllocations) {
  long seen;
  {
    Count c;
    std::vector<double>* v = new std::vector<double>(100);
    Eigen::VectorXd* e = new Eigen::VectorXd(50);
    seen = c.value();
    delete v;
    delete e;
  }
  EXPECT_GE(seen, 3);
}

TEST(Realtime, DynamicsPathsAllocateNothing) {
  for (const auto& [name, model] : test::chainsAndTrees()) {
    Data data(model);
    const int n = model.nq();
    const ParameterLayout layout{true, true};
    const Eigen::VectorXd pi = model.parameters(layout);
    std::mt19937 rng(21);
    const Eigen::VectorXd q = test::random(rng, n), dq = test::random(rng, n),
                          ddq = test::random(rng, n);
    Eigen::VectorXd tau(n), ddq2(n), wK(layout.size(n)), wP(layout.size(n));
    Eigen::MatrixXd W(n, layout.size(n)), M(n, n), Wp(n, layout.size(n));
    double e = 0;
    bool ok = true;
    Count c;
    for (int i = 0; i < 3; ++i) {
      inverseDynamics(model, data, q, dq, ddq, pi, layout, tau);
      gravityTorque(model, data, q, pi, layout, tau);
      regressor(model, data, q, dq, ddq, layout, W);
      energyRegressors(model, data, q, dq, layout, wK, wP);
      momentumRegressors(model, data, q, dq, layout, Wp, W);
      e += kineticEnergy(model, data, q, dq, pi, layout) +
           potentialEnergy(model, data, q, pi, layout);
      massMatrix(model, data, q, pi, layout, M);
      ok = ok && forwardDynamics(model, data, q, dq, tau, pi, layout, ddq2);
    }
    const long seen = c.value();
    EXPECT_EQ(seen, 0) << name;
    EXPECT_TRUE(ok);
    EXPECT_TRUE(std::isfinite(e));
  }
}

TEST(Realtime, BaseRegressorsAllocateNothing) {
  for (const char* name : {"puma560", "zcr07s", "stanford"}) {
    const Model model = loadYaml(test::robotFile(name));
    const ParameterLayout layout{true, true};
    BaseOptions options;
    options.layout = layout;
    const BaseParameters base = computeBaseParameters(model, options);
    Data data(model);
    const int n = model.nq(), P = layout.size(n), nb = base.eom.size();
    std::mt19937 rng(5);
    const Eigen::VectorXd q = test::random(rng, n), dq = test::random(rng, n),
                          ddq = test::random(rng, n);
    Eigen::MatrixXd W(n, P), Wb(n, nb), Wp(n, P), Wl(n, P), Wpb(n, nb), Wlb(n, nb);
    Eigen::VectorXd wK(P), wP(P), wb(nb);
    long seen;
    {
      Count c;
      for (int i = 0; i < 3; ++i) {
        baseMomentumRegressors(model, data, base, q, dq, Wp, Wl, Wpb, Wlb);
        baseRegressor(model, data, base, q, dq, ddq, W, Wb);
        baseEnergyRegressor(model, data, base, q, dq, wK, wP, wb);
      }
      seen = c.value();
    }
    EXPECT_EQ(seen, 0) << name;
    // and they are the pivot columns of the classical regressors
    for (int b = 0; b < nb; ++b) {
      EXPECT_EQ(Wb.col(b), W.col(base.eom.decision.pivots[b])) << name;
      EXPECT_EQ(wb[b], wK[base.eom.decision.pivots[b]] + wP[base.eom.decision.pivots[b]]);
    }
  }
}

TEST(Realtime, SlotineLiPathsAllocateNothing) {
  for (const auto& [name, model] : test::chainsAndTrees()) {
    Data data(model);
    const int n = model.nq();
    const ParameterLayout layout{true, true};
    BaseOptions options;
    options.layout = layout;
    const BaseParameters bp = computeBaseParameters(model, options);
    SlotineLiData sl(model, layout);
    const Eigen::VectorXd pi = model.parameters(layout);
    std::mt19937 rng(22);
    const Eigen::VectorXd q = test::random(rng, n), dq = test::random(rng, n),
                          dqr = test::random(rng, n), ddqr = test::random(rng, n);
    Eigen::VectorXd tau(n);
    Eigen::MatrixXd Y(n, layout.size(n)), Yb(n, bp.eom.size()), C(n, n);
    Count c;
    for (int i = 0; i < 3; ++i) {
      slotineLiRegressor(model, data, sl, q, dq, dqr, ddqr, layout, Y);
      slotineLiBaseRegressor(model, data, sl, bp, q, dq, dqr, ddqr, Yb);
      slotineLiTorque(model, data, sl, q, dq, dqr, ddqr, pi, layout, tau);
      coriolisMatrix(model, data, sl, q, dq, pi, layout, C);
    }
    const long seen = c.value();
    EXPECT_EQ(seen, 0) << name;
    EXPECT_TRUE(Yb.allFinite() && tau.allFinite() && C.allFinite());
  }
}

TEST(Realtime, OffsetLayoutsAllocateNothing) {
  for (const auto& [name, model] : test::chainsAndTrees()) {
    Data data(model);
    const int n = model.nq();
    ParameterLayout layout{true, true};
    layout.offset = true;
    BaseOptions options;
    options.layout = layout;
    const BaseParameters bp = computeBaseParameters(model, options);
    SlotineLiData sl(model, layout);
    const Eigen::VectorXd pi = model.parameters(layout);
    std::mt19937 rng(23);
    const Eigen::VectorXd q = test::random(rng, n), dq = test::random(rng, n),
                          ddq = test::random(rng, n);
    const int P = layout.size(n), nb = bp.eom.size();
    Eigen::VectorXd tau(n), ddq2(n), wK(P), wP(P), wb(nb);
    Eigen::MatrixXd W(n, P), Wp(n, P), Wb(n, nb), Wpb(n, nb), Wlb(n, nb), Y(n, P);
    bool ok = true;
    Count c;
    for (int i = 0; i < 3; ++i) {
      inverseDynamics(model, data, q, dq, ddq, pi, layout, tau);
      regressor(model, data, q, dq, ddq, layout, W);
      energyRegressors(model, data, q, dq, layout, wK, wP);
      momentumRegressors(model, data, q, dq, layout, Wp, W);
      ok = ok && forwardDynamics(model, data, q, dq, tau, pi, layout, ddq2);
      baseRegressor(model, data, bp, q, dq, ddq, W, Wb);
      baseEnergyRegressor(model, data, bp, q, dq, wK, wP, wb);
      baseMomentumRegressors(model, data, bp, q, dq, Wp, W, Wpb, Wlb);
      slotineLiRegressor(model, data, sl, q, dq, dq, ddq, layout, Y);
      slotineLiTorque(model, data, sl, q, dq, dq, ddq, pi, layout, tau);
    }
    const long seen = c.value();
    EXPECT_EQ(seen, 0) << name;
    EXPECT_TRUE(ok && Wb.allFinite() && wb.allFinite() && Wlb.allFinite() && tau.allFinite());
  }
}

TEST(Realtime, InverseKinematicsAllocatesNothing) {
  for (const char* name : {"puma560", "zcr07s"}) {
    const Model model = loadYaml(test::robotFile(name));
    IkSolver solver(model);
    ChainKinematics chain(model);
    const int n = model.nq();
    std::mt19937 rng(23);
    Eigen::VectorXd q(n);
    Matrix6Xd J(6, n);
    Eigen::Isometry3d T;
    std::vector<Eigen::Isometry3d> targets;
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int i = 0; i < 5; ++i) {
      for (int k = 0; k < n; ++k)
        q[k] = solver.lower()[k] + u(rng) * (solver.upper()[k] - solver.lower()[k]);
      chain.pose(q, T);
      targets.push_back(T);
      q[i % n] = solver.upper()[i % n];  // a joint at its limit: the refinement holds it there
      chain.pose(q, T);
      targets.push_back(T);
    }
    Eigen::Isometry3d far = Eigen::Isometry3d::Identity();
    far.translation() << 9.0, 0.0, 0.0;
    targets.push_back(far);  // fails after restarts: exercises every path
    const Eigen::VectorXd q0 = Eigen::VectorXd::Zero(n);
    int converged = 0;
    Count c;
    for (const auto& target : targets) {
      converged += solver.solve(target, q0, q).success();
      chain.poseAndJacobian(q, T, J);
    }
    const long seen = c.value();
    EXPECT_EQ(seen, 0) << name;
    EXPECT_EQ(converged, 10) << name;
  }
}

TEST(Realtime, IntegratorStepsAllocateNothing) {
  const Model model = loadYaml(test::robotFile("zcr07s"));
  const ParameterLayout layout{true, true};
  Integrator integ(model, model.parameters(layout), layout, 0.01);
  Data data(model);
  Eigen::VectorXd q = Eigen::VectorXd::Constant(6, 0.1), dq = Eigen::VectorXd::Constant(6, 0.2),
                  tau = Eigen::VectorXd::Constant(6, 1.0), ddq(6);
  long seen;
  {
    Count c;
    integ.step(data, q, dq, tau, 0.004, 4);
    integ.acceleration(data, q, dq, tau, ddq);
    seen = c.value();
  }
  EXPECT_EQ(seen, 0);
  EXPECT_TRUE(q.allFinite() && dq.allFinite());
}

TEST(Realtime, MotorSidePathsAllocateNothing) {
  // Rotor inertia and friction on the motors of a coupled transmission (motor 6 turns with
  // joints 5 and 6).
  Model model = loadYaml(test::robotFile("zcr07s"));
  const int n = model.nq();
  Transmission& tr = model.transmission;
  tr.format = "yaml";
  tr.T = 50.0 * Eigen::MatrixXd::Identity(n, n);
  tr.T(n - 1, n - 2) = 30.0;
  tr.offset = Eigen::VectorXd::Zero(n);
  tr.torque_constant = Eigen::VectorXd::Constant(n, std::nan(""));
  for (int k = 0; k < n; ++k) {
    tr.motors.push_back("m" + std::to_string(k + 1));
    tr.types.push_back("matrix");
  }
  ASSERT_TRUE(model.motorSide());
  const ParameterLayout layout{true, true};
  Eigen::VectorXd pi = model.parameters(layout);
  for (int k = 0; k < n; ++k) {
    pi[layout.rotorIndex(k)] = 1e-4;
    pi[layout.viscousIndex(k)] = 1e-3;
    pi[layout.coulombIndex(k)] = 0.02;
  }
  BaseOptions options;
  options.layout = layout;
  const BaseParameters bp = computeBaseParameters(model, options);
  Data data(model);
  SlotineLiData sl(model, layout);
  Integrator integ(model, pi, layout, 0.01);
  std::mt19937 rng(23);
  const Eigen::VectorXd q = test::random(rng, n), dq = test::random(rng, n),
                        ddq = test::random(rng, n);
  Eigen::VectorXd tau(n), ddq2(n), wK(layout.size(n)), wP(layout.size(n));
  Eigen::MatrixXd W(n, layout.size(n)), M(n, n), Wp(n, layout.size(n)), Yb(n, bp.eom.size());
  Eigen::VectorXd x = q, v = dq;
  bool ok = true;
  long seen;
  {
    Count c;
    inverseDynamics(model, data, q, dq, ddq, pi, layout, tau);
    regressor(model, data, q, dq, ddq, layout, W);
    energyRegressors(model, data, q, dq, layout, wK, wP);
    momentumRegressors(model, data, q, dq, layout, Wp, W);
    ok = std::isfinite(kineticEnergy(model, data, q, dq, pi, layout));
    massMatrix(model, data, q, pi, layout, M);
    ok = ok && forwardDynamics(model, data, q, dq, tau, pi, layout, ddq2);
    slotineLiBaseRegressor(model, data, sl, bp, q, dq, dq, ddq, Yb);
    slotineLiTorque(model, data, sl, q, dq, dq, ddq, pi, layout, tau);
    ok = ok && integ.step(data, x, v, tau, 0.004, 2);
    seen = c.value();
  }
  EXPECT_EQ(seen, 0);
  EXPECT_TRUE(ok);
  // The motor terms are there: the mass matrix has Ia t_6 t_6^T off the diagonal.
  EXPECT_NEAR(M(n - 1, n - 2) - M(n - 2, n - 1), 0.0, 1e-12);
  Model joint = model;
  joint.drive_terms_on_motors = false;
  Eigen::MatrixXd Mj(n, n);
  massMatrix(joint, data, q, pi, layout, Mj);
  EXPECT_NEAR(M(n - 1, n - 2) - Mj(n - 1, n - 2), 1e-4 * 30.0 * 50.0, 1e-12);
}

// Every friction model on the per-call paths: no allocation, and the regressor's friction
// columns equal the models' formulas written out here.
TEST(Realtime, FrictionModelsAllocateNothing) {
  Model model = loadYaml(test::robotFile("puma560"));
  const int n = model.nq();
  for (FrictionKind kind : {FrictionKind::Coulomb, FrictionKind::Asymmetric, FrictionKind::Smooth,
                            FrictionKind::Stribeck}) {
    model.friction_model.kind = kind;
    model.friction_model.velocity = model.friction_model.scaled()
                                        ? Eigen::VectorXd::LinSpaced(n, 0.05, 0.3)
                                        : Eigen::VectorXd();
    model.third_friction = Eigen::VectorXd::LinSpaced(n, 0.5, 1.0);
    const ParameterLayout layout = model.layout(true, true);
    checkSizes(model, layout, n, n, n, layout.size(n));
    const Eigen::VectorXd pi = model.parameters(layout);
    std::mt19937 rng(5);
    Eigen::VectorXd q = test::random(rng, n), dq = test::random(rng, n), ddq = test::random(rng, n);
    dq[1] = 0.0;
    Eigen::VectorXd tau(n), ddq2(n);
    Eigen::MatrixXd W(n, layout.size(n));
    Integrator integ(model, pi, layout, 0.0);
    Data data(model);
    bool ok = true;
    {
      Count c;
      inverseDynamics(model, data, q, dq, ddq, pi, layout, tau);
      regressor(model, data, q, dq, ddq, layout, W);
      ok = integ.acceleration(data, q, dq, tau, ddq2);
      EXPECT_EQ(c.value(), 0) << toString(kind);
    }
    EXPECT_TRUE(ok);
    EXPECT_LT((ddq2 - ddq).norm(), 1e-8 * (1 + ddq.norm())) << toString(kind);
    EXPECT_LT((W * pi - tau).norm(), 1e-9 * (1 + tau.norm())) << toString(kind);
    for (int k = 0; k < n; ++k) {
      const double v = dq[k], s = v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0);
      const double w = model.friction_model.scaled() ? model.friction_model.velocity[k] : 1.0;
      EXPECT_EQ(W(k, layout.viscousIndex(k)), v);
      const double c1 = kind == FrictionKind::Smooth ? std::tanh(v / w) : s;
      EXPECT_DOUBLE_EQ(W(k, layout.coulombIndex(k)), c1) << toString(kind);
      if (layout.friction_columns == 3) {
        const double c2 =
            kind == FrictionKind::Asymmetric ? std::abs(s) : s * std::exp(-(v / w) * (v / w));
        EXPECT_DOUBLE_EQ(W(k, layout.thirdFrictionIndex(k)), c2) << toString(kind);
      }
    }
  }
}

TEST(Realtime, MultibodyPathsAllocateNothing) {
  for (const char* convention : {"mdh", "dh"}) {
    const Model model = test::everyJointKind(convention);
    MultibodyData data(model);
    const int nv = model.velocitySize(), n = model.nq();
    std::mt19937 rng(4);
    Eigen::VectorXd q(model.configSize());
    randomConfiguration(model, rng, q);
    const Eigen::VectorXd v = test::random(rng, nv), a = test::random(rng, nv);
    Eigen::VectorXd tau(nv), a2(nv);
    Eigen::MatrixXd W(nv, 10 * n), M(nv, nv), C(nv, nv), J(6, nv);
    Eigen::Isometry3d placement = Eigen::Isometry3d::Identity();
    placement.translation() << 0.1, -0.2, 0.3;
    double e = 0;
    bool ok = true;
    test::Count c;
    for (int i = 0; i < 3; ++i) {
      inverseDynamics(model, data, q, v, a, model.inertial, tau);
      regressor(model, data, q, v, a, W);
      massMatrix(model, data, q, model.inertial, M);
      ok = ok && forwardDynamics(model, data, q, v, tau, model.inertial, a2);
      slotineLiRegressor(model, data, q, v, a, v, W);
      coriolisMatrix(model, data, q, v, model.inertial, C);
      e += momentum(model, data, q, v, model.inertial).norm();
      e += kineticEnergy(model, data, q, v, model.inertial) +
           potentialEnergy(model, data, q, model.inertial);
      for (const auto frame : {ReferenceFrame::LocalWorldAligned, ReferenceFrame::Local}) {
        frameJacobian(model, data, q, n - 1, placement, frame, J);
        e += J.norm();
      }
    }
    EXPECT_EQ(c.value(), 0) << convention;
    EXPECT_TRUE(ok);
    EXPECT_TRUE(std::isfinite(e));
  }
}
