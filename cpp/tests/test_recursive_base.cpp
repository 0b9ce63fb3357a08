// The recursive method against the projection method (same base set, same Y) and, for chains
// the projection does not reach and for trees, against the sampled regressor (its count, and
// W_b Y pi = W pi).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <random>

#include "mindyn/base_parameters.hpp"
#include "mindyn/recursive_base.hpp"
#include "mindyn/urdf.hpp"
#include "test_util.hpp"

using namespace mindyn;

namespace {

BaseParameters compute(const Model& model, ParameterLayout layout, BaseMethod method) {
  BaseOptions opt;
  opt.layout = layout;
  opt.method = method;
  return computeBaseParameters(model, opt);
}

// Same base set, same Y, same counts of the three sets.
void expectSame(const Model& model, ParameterLayout layout) {
  const BaseParameters proj = compute(model, layout, BaseMethod::Projection);
  const BaseParameters rec = compute(model, layout, BaseMethod::Recursive);
  const std::string what = model.name + (layout.rotor ? " +Ia+F" : "");
  EXPECT_EQ(rec.eom.names, proj.eom.names) << what;
  EXPECT_EQ(rec.lagrangian.names, proj.lagrangian.names) << what;
  EXPECT_EQ(rec.energy.names, proj.energy.names) << what;
  EXPECT_EQ(rec.lagrangian_equals_eom, proj.lagrangian_equals_eom) << what;
  ASSERT_EQ(rec.eom.decision.Y.rows(), proj.eom.decision.Y.rows()) << what;
  // Y is determined by the nullspace and the pivots; both are computed to rounding.
  EXPECT_LT((Eigen::MatrixXd(rec.eom.decision.Y) - Eigen::MatrixXd(proj.eom.decision.Y))
                .cwiseAbs()
                .maxCoeff(),
            1e-10)
      << what;
  ASSERT_EQ(rec.lagrangian.decision.Y.rows(), proj.lagrangian.decision.Y.rows()) << what;
  EXPECT_LT(
      (Eigen::MatrixXd(rec.lagrangian.decision.Y) - Eigen::MatrixXd(proj.lagrangian.decision.Y))
          .cwiseAbs()
          .maxCoeff(),
      1e-10)
      << what;
  EXPECT_FALSE(rec.eom.decision.near_degenerate) << what;
}

// The recursive base set reproduces the torques of random parameters at random states, and
// its count is the rank of the sampled regressor.
void expectTorquesAndNumericalCount(const Model& model, ParameterLayout layout, std::mt19937& rng) {
  const BaseParameters rec = compute(model, layout, BaseMethod::Recursive);
  const BaseParameters num = compute(model, layout, BaseMethod::Numerical);
  const std::string what =
      model.name + (layout.rotor ? " +Ia" : "") + (layout.friction ? " +F" : "");
  EXPECT_EQ(rec.eom.size(), num.eom.size()) << what;
  EXPECT_EQ(rec.lagrangian.size(), num.lagrangian.size()) << what;
  // The regressors at three random states, stacked.
  Data data(model);
  const int n = model.nq(), P = layout.size(n), nb = rec.eom.size();
  Eigen::MatrixXd W(n, P), Wb(n, nb), Ws(3 * n, P), Wbs(3 * n, nb);
  for (int s = 0; s < 3; ++s) {
    baseRegressor(model, data, rec, test::random(rng, n, 2.5), test::random(rng, n, 1.5),
                  test::random(rng, n, 3), W, Wb);
    Ws.middleRows(s * n, n) = W;
    Wbs.middleRows(s * n, n) = Wb;
  }
  // W = W_b Y column by column: every classical column is the base columns' combination Y
  // says. 1e-9 relative: sums of a few hundred terms at rounding 1e-16, Y's entries (lever
  // arms out to the 20th link) up to about 1e3.
  const Eigen::MatrixXd err = Wbs * Eigen::MatrixXd(rec.eom.decision.Y) - Ws;
  EXPECT_LT(err.norm(), 1e-9 * Ws.norm()) << what;
  // And so the torques of random parameters: W pi = W_b (Y pi).
  for (int t = 0; t < 2; ++t) {
    const Eigen::VectorXd pi = test::random(rng, P);
    const Eigen::VectorXd tau = Ws * pi;
    EXPECT_LT((Wbs * rec.values(pi) - tau).norm(), 1e-9 * Ws.norm() * pi.norm()) << what;
  }
}

}  // namespace

TEST(RecursiveBase, SameSetAndYAsProjectionOnTheBundledRobots) {
  for (const std::string& name : test::bundled())
    for (ParameterLayout layout : {ParameterLayout{false, false}, ParameterLayout{true, true}})
      expectSame(loadYaml(test::robotFile(name)), layout);
  for (bool vertical : {true, false})
    for (ParameterLayout layout : {ParameterLayout{false, false}, ParameterLayout{true, false}})
      expectSame(planarArm(6, vertical), layout);
}

TEST(RecursiveBase, SameSetAndYAsProjectionOnRandomChains) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 12; ++trial) {
    const bool special = trial % 3 != 0;
    const Model m = test::randomChain(rng, special ? 6 : 4, trial % 2 == 0, special);
    expectSame(m, {false, false});
    expectSame(m, {true, true});
  }
}

TEST(RecursiveBase, SameSetAndYAsProjectionOnRandomTrees) {
  std::mt19937 rng(23);
  for (int trial = 0; trial < 12; ++trial) {
    const bool special = trial % 3 != 0;
    const Model m = test::randomChain(rng, 4 + trial % 5, trial % 2 == 0, special, true);
    expectSame(m, {false, false});
    expectSame(m, {true, true});
  }
}

TEST(RecursiveBase, LongChainsMatchTheSampledRegressor) {
  std::mt19937 rng(5);
  expectTorquesAndNumericalCount(planarArm(20, true), {true, true}, rng);
  expectTorquesAndNumericalCount(test::randomChain(rng, 20, true, false), {true, true}, rng);
  expectTorquesAndNumericalCount(test::randomChain(rng, 20, true, true), {false, false}, rng);
}

// A prismatic joint along the axis of the revolute joint before it, both horizontal: its rotor
// inertia regroups with the masses of its link and the link before (a unit mass at the same
// point of each), though the link before rotates.
TEST(RecursiveBase, PrismaticRotorAlongTheRotationBeforeIt) {
  Model m;
  m.name = "rpr";
  m.link_names = {"base", "l1", "l2", "l3"};
  const Eigen::Vector3d axes[3] = {Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitY(),
                                   Eigen::Vector3d::UnitZ()};
  for (int k = 0; k < 3; ++k) {
    Joint j;
    j.name = "j" + std::to_string(k + 1);
    j.type = k == 1 ? JointType::Prismatic : JointType::Revolute;
    j.axis = axes[k];
    j.pre.translation() = Eigen::Vector3d(0.3, 0.1 * k, 0.2);
    m.joints.push_back(j);
  }
  std::mt19937 rng(3);
  m.inertial = test::random(rng, 30);
  m.rotor_inertia = m.viscous = m.coulomb = Eigen::Vector3d::Ones();
  m.gravity = Eigen::Vector3d(0, 0, -9.81);
  expectSame(m, {true, true});
  expectTorquesAndNumericalCount(m, {true, false}, rng);
  const BaseParameters rec = compute(m, {true, false}, BaseMethod::Recursive);
  for (const std::string& name : rec.eom.names) EXPECT_NE(name, "Ia2");
}

// Trees: each joint's parent drawn at random among the base and the joints before it, general or
// special (parallel, perpendicular, axis-aligned) axes, revolute and prismatic joints, with and
// without rotor inertia and friction.
TEST(RecursiveBase, TreesMatchTheSampledRegressor) {
  std::mt19937 rng(29);
  for (int n = 3; n <= 20; ++n)
    for (bool special : {false, true}) {
      const Model m = test::randomChain(rng, n, true, special, /*tree=*/true);
      if (m.isSerial()) continue;  // (a draw may happen to be a chain)
      expectTorquesAndNumericalCount(m, {false, false}, rng);
      expectTorquesAndNumericalCount(
          m, n % 2 ? ParameterLayout{true, true} : ParameterLayout{true, false}, rng);
    }
}

// Two PUMA 560 on the one base: the base set is the serial arm's (from the projection method)
// twice, the second with its joint numbers moved by 6, and Y the serial Y twice on the diagonal.
TEST(RecursiveBase, TwoArmsOnOneBaseAreTheSerialArmTwice) {
  const Model arm = loadYaml(test::robotFile("puma560"));
  const int n = arm.nq();
  Model two = arm;
  two.name = "two puma560";
  two.joints.insert(two.joints.end(), arm.joints.begin(), arm.joints.end());
  for (int k = 0; k < n; ++k) two.link_names.push_back(arm.link_names[k + 1] + "_b");
  for (int k = n; k < 2 * n; ++k) two.joints[k].name += "_b";
  two.inertial.resize(20 * n);
  two.inertial << arm.inertial, arm.inertial;
  for (Eigen::VectorXd* v : {&two.rotor_inertia, &two.viscous, &two.coulomb}) {
    const Eigen::VectorXd one = *v;
    v->resize(2 * n);
    *v << one, one;
  }
  for (int k = 0; k < 2 * n; ++k) two.parents.push_back(k == 0 || k == n ? -1 : k - 1);
  for (ParameterLayout layout : {ParameterLayout{false, false}, ParameterLayout{true, true}}) {
    const BaseParameters one = compute(arm, layout, BaseMethod::Projection);
    const BaseParameters rec = compute(two, layout, BaseMethod::Recursive);
    std::vector<std::string> names = one.eom.names;
    for (const std::string& name : one.eom.names) {  // XXR3 -> XXR9
      size_t d = name.size();
      while (d > 0 && std::isdigit(static_cast<unsigned char>(name[d - 1]))) --d;
      names.push_back(name.substr(0, d) + std::to_string(std::stoi(name.substr(d)) + n));
    }
    EXPECT_EQ(rec.eom.names, names);
    const Eigen::MatrixXd Y1(one.eom.decision.Y);
    Eigen::MatrixXd Y = Eigen::MatrixXd::Zero(2 * Y1.rows(), 2 * Y1.cols());
    Y.topLeftCorner(Y1.rows(), Y1.cols()) = Y1;
    Y.bottomRightCorner(Y1.rows(), Y1.cols()) = Y1;
    ASSERT_EQ(rec.eom.decision.Y.rows(), Y.rows());
    // Both exact to rounding (entries up to about 1 here).
    EXPECT_LT((Eigen::MatrixXd(rec.eom.decision.Y) - Y).cwiseAbs().maxCoeff(), 1e-10);
  }
}

TEST(RecursiveBase, RowsAreIndependentAndCountedPerLink) {
  const Model m = loadYaml(test::robotFile("puma560"));
  const IdentifiableSpace s = recursiveIdentifiable(m, {}, kDefaultRankTolerance);
  int sum = 0;
  for (int r : s.link_rank) sum += r;
  EXPECT_EQ(sum, s.rows.rows());
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(Eigen::MatrixXd(s.rows));
  EXPECT_EQ(svd.rank(), s.rows.rows());
}

TEST(RecursiveBase, RefusesAnInvalidModel) {
  Model m = loadYaml(test::robotFile("puma560"));
  m.joints[2].axis = Eigen::Vector3d(std::nan(""), 0.0, 1.0);
  EXPECT_THROW(compute(m, {}, BaseMethod::Recursive), ModelError);
}

// Multi-DOF joints (every kind, in MDH and DH frames): the exact methods, on the single-DOF
// expansion, give the numerical method's count (sampled multibody regressors) and agree on the
// base set and Y; each set reproduces the classical dynamics (checked inside), and the
// floating body's ten parameters are all base parameters.
TEST(RecursiveBase, MultiDofModelsGiveTheNumericalCount) {
  for (const char* convention : {"mdh", "dh"}) {
    const Model model = test::everyJointKind(convention);
    BaseOptions opt;
    opt.method = BaseMethod::Numerical;
    const int count = computeBaseParameters(model, opt).eom.size();
    opt.method = BaseMethod::Recursive;
    const BaseParameters rec = computeBaseParameters(model, opt);
    opt.method = BaseMethod::Projection;
    const BaseParameters proj = computeBaseParameters(model, opt);
    EXPECT_EQ(rec.eom.size(), count) << convention;
    EXPECT_EQ(proj.eom.size(), count) << convention;
    EXPECT_EQ(rec.eom.decision.pivots, proj.eom.decision.pivots) << convention;
    EXPECT_EQ(rec.lagrangian.size(), proj.lagrangian.size()) << convention;
    const Eigen::MatrixXd d = Eigen::MatrixXd(rec.eom.decision.Y) - proj.eom.decision.Y;
    EXPECT_LE(d.cwiseAbs().maxCoeff(), 1e-9) << convention;
    for (int c = 0; c < 10; ++c)
      EXPECT_NE(std::find(rec.eom.decision.pivots.begin(), rec.eom.decision.pivots.end(), c),
                rec.eom.decision.pivots.end())
          << convention << " column " << c;
  }
}
