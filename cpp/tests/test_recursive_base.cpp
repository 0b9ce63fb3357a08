// The recursive method against the projection method (same base set, same Y) and, for chains
// the projection does not reach, against the sampled regressor (its count, and W_b Y pi = W pi).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
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
  EXPECT_LT((rec.eom.decision.Y - proj.eom.decision.Y).cwiseAbs().maxCoeff(), 1e-10) << what;
  ASSERT_EQ(rec.lagrangian.decision.Y.rows(), proj.lagrangian.decision.Y.rows()) << what;
  EXPECT_LT((rec.lagrangian.decision.Y - proj.lagrangian.decision.Y).cwiseAbs().maxCoeff(), 1e-10)
      << what;
  EXPECT_FALSE(rec.eom.decision.near_degenerate) << what;
}

// The recursive base set reproduces the torques of random parameters at random states, and
// its count is the rank of the sampled regressor.
void expectTorquesAndNumericalCount(const Model& model, ParameterLayout layout, std::mt19937& rng) {
  const BaseParameters rec = compute(model, layout, BaseMethod::Recursive);
  const BaseParameters num = compute(model, layout, BaseMethod::Numerical);
  EXPECT_EQ(rec.eom.size(), num.eom.size()) << model.name;
  EXPECT_EQ(rec.lagrangian.size(), num.lagrangian.size()) << model.name;
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
  const Eigen::MatrixXd err = Wbs * rec.eom.decision.Y - Ws;
  EXPECT_LT(err.norm(), 1e-9 * Ws.norm()) << model.name;
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

TEST(RecursiveBase, LongChainsMatchTheSampledRegressor) {
  std::mt19937 rng(5);
  expectTorquesAndNumericalCount(planarArm(20, true), {true, true}, rng);
  expectTorquesAndNumericalCount(test::randomChain(rng, 20, true, false), {true, true}, rng);
  expectTorquesAndNumericalCount(test::randomChain(rng, 20, true, true), {false, false}, rng);
}

TEST(RecursiveBase, RowsAreIndependentAndCountedPerLink) {
  const Model m = loadYaml(test::robotFile("puma560"));
  const IdentifiableSpace s = recursiveIdentifiable(m, {}, kDefaultRankTolerance);
  int sum = 0;
  for (int r : s.link_rank) sum += r;
  EXPECT_EQ(sum, s.rows.rows());
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(s.rows);
  EXPECT_EQ(svd.rank(), s.rows.rows());
}

TEST(RecursiveBase, RefusesAnInvalidModel) {
  Model m = loadYaml(test::robotFile("puma560"));
  m.joints[2].axis = Eigen::Vector3d(std::nan(""), 0.0, 1.0);
  EXPECT_THROW(compute(m, {}, BaseMethod::Recursive), ModelError);
}
