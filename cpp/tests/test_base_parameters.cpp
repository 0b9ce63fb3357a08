// Base parameters reproduce the torques (W_b Y pi = W pi, and through the classical algorithm
// with the embedded base vector) and agree in number with the numerical method.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <sstream>

#include "mindyn/base_parameters.hpp"
#include "mindyn/projection.hpp"
#include "mindyn/urdf.hpp"
#include "test_util.hpp"
#include "tree_paths.hpp"

using namespace mindyn;

namespace {

// A chain with skewed axes, offsets everywhere, a prismatic joint and non-identity post frames.
Model skewedArm(std::mt19937& rng) {
  const std::string dh = R"(
convention: dh
angle_unit: deg
joints:
  - {a: 0.05, alpha: 73, d: 0.3, theta: 11}
  - {a: 0.4, alpha: -17, d: 0.02, theta: 40}
  - {type: prismatic, a: 0.03, alpha: 61, d: 0.1, theta: -25}
  - {a: 0.0, alpha: 88, d: 0.35, theta: 5}
  - {a: 0.02, alpha: -95, d: 0.01, theta: 0}
)";
  Model m = parseYaml(dh, "skewed");
  m.inertial = test::random(rng, 10 * m.nq());
  m.gravity = Eigen::Vector3d(0.3, -1.2, -9.7);
  return m;
}

}  // namespace

TEST(BaseParameters, ReproduceTheTorquesAndMatchTheNumericalCount) {
  std::mt19937 rng(32);
  std::vector<Model> models = {loadYaml(test::robotFile("puma560")),
                               loadYaml(test::robotFile("zcr07s")), skewedArm(rng)};
  for (const Model& model : models) {
    for (ParameterLayout layout : {ParameterLayout{false, false}, ParameterLayout{true, true}}) {
      BaseOptions opt;
      opt.layout = layout;
      const BaseParameters bp = computeBaseParameters(model, opt);
      opt.method = BaseMethod::Numerical;
      const BaseParameters num = computeBaseParameters(model, opt);
      EXPECT_EQ(bp.eom.size(), num.eom.size()) << model.name;
      EXPECT_EQ(bp.lagrangian.size(), num.lagrangian.size()) << model.name;
      Data data(model);
      const int n = model.nq(), P = layout.size(n);
      Eigen::MatrixXd W(n, P), Wb(n, bp.eom.size());
      for (int trial = 0; trial < 5; ++trial) {
        const Eigen::VectorXd pi = test::random(rng, P);
        const Eigen::VectorXd q = test::random(rng, n, 2.5), dq = test::random(rng, n, 1.5),
                              ddq = test::random(rng, n, 3);
        baseRegressor(model, data, bp, q, dq, ddq, W, Wb);
        const Eigen::VectorXd tau = W * pi;
        EXPECT_LT((Wb * bp.values(pi) - tau).norm(), 1e-10 * std::max(1.0, tau.norm()))
            << model.name;
        // The embedded base vector gives the same torques through the classical algorithm.
        Eigen::VectorXd tau2(n);
        inverseDynamics(model, data, q, dq, ddq, bp.embed(bp.values(pi)), layout, tau2);
        EXPECT_LT((tau2 - tau).norm(), 1e-10 * std::max(1.0, tau.norm())) << model.name;
      }
    }
  }
}

namespace {

// W(:, pivots) Y pi = W pi for the equations-of-motion set, and the same for the Lagrangian and
// total-energy sets on their energy regressors, the references assembled from the serial chains
// of the root paths.
void expectTreeSetsReproduce(const Model& model, const BaseParameters& bp, std::mt19937& rng,
                             const std::string& what) {
  const ParameterLayout layout = bp.layout;
  const int n = model.nq(), P = layout.size(n);
  auto pick = [](const Eigen::VectorXd& w, const BaseSet& set) {
    Eigen::VectorXd out(set.size());
    for (int b = 0; b < set.size(); ++b) out[b] = w[set.decision.pivots[b]];
    return out;
  };
  for (int trial = 0; trial < 4; ++trial) {
    const Eigen::VectorXd pi = test::random(rng, P);
    const Eigen::VectorXd q = test::random(rng, n, 2.5), dq = test::random(rng, n, 1.5),
                          ddq = test::random(rng, n, 3);
    const Eigen::MatrixXd W = test::pathRegressor(model, q, dq, ddq, layout);
    const Eigen::VectorXd tau = W * pi;
    // The library's base regressor on the tree against the reference torques; rounding of sums
    // of a few hundred terms of size ~10: far below 1e-10 relative.
    Data data(model);
    Eigen::MatrixXd Wl(n, P), Wb(n, bp.eom.size());
    baseRegressor(model, data, bp, q, dq, ddq, Wl, Wb);
    EXPECT_LT((Wb * bp.values(pi) - tau).norm(), 1e-10 * std::max(1.0, tau.norm())) << what;
    for (bool total : {false, true}) {
      const BaseSet& set = total ? bp.energy : bp.lagrangian;
      const Eigen::VectorXd w = test::pathEnergyRegressor(model, q, dq, layout, total);
      const double e = w.dot(pi);
      EXPECT_LT(std::abs(pick(w, set).dot(set.decision.Y * pi) - e),
                1e-10 * std::max(1.0, std::abs(e)))
          << what << (total ? " total energy" : " Lagrangian");
    }
  }
}

}  // namespace

// Random trees: the projection method's sets reproduce the torques and energies, and their
// counts are the ranks of the sampled reference regressors.
TEST(BaseParameters, RandomTreesReproduceTheTorquesAndEnergies) {
  std::mt19937 rng(41);
  for (const Model& model : test::testTrees(rng))
    for (ParameterLayout layout : {ParameterLayout{false, false}, ParameterLayout{true, true}}) {
      const int n = model.nq();
      const std::string what = model.name + (layout.rotor ? " Ia+Fv+Fc" : "");
      BaseOptions opt;
      opt.layout = layout;
      const BaseParameters bp = computeBaseParameters(model, opt);
      const int P = layout.size(n);
      EXPECT_EQ(bp.eom.size(), test::sampledRank(model, layout, 3 * P / n + 20, rng)) << what;
      EXPECT_EQ(bp.lagrangian.size(), test::sampledRank(model, layout, P + 20, rng, true)) << what;
      opt.method = BaseMethod::Numerical;
      const BaseParameters num = computeBaseParameters(model, opt);
      EXPECT_EQ(bp.eom.size(), num.eom.size()) << what;
      EXPECT_EQ(bp.lagrangian.size(), num.lagrangian.size()) << what;
      EXPECT_EQ(bp.energy.size(), num.energy.size()) << what;
      expectTreeSetsReproduce(model, bp, rng, what);
    }
}

// Two copies of an arm mounted on the base: each branch regroups within itself exactly as the
// arm alone (the names relabelled by the number of joints of the first copy, the same Y), and
// the torque set is the two arms' together.
TEST(BaseParameters, TwoCopiesOfAnArmOnTheBase) {
  std::mt19937 rng(43);
  std::vector<Model> arms = {loadYaml(test::robotFile("puma560")),
                             loadYaml(test::robotFile("stanford")), skewedArm(rng),
                             test::randomChain(rng, 5, true, true)};
  for (Model& arm : arms) {
    arm = test::withExtras(arm, rng);
    const int m = arm.nq();
    Model tree = arm;
    tree.name = arm.name + "_twice";
    for (int k = 0; k < m; ++k) {
      Joint j = arm.joints[static_cast<size_t>(k)];
      j.name += "_b";
      tree.joints.push_back(j);
      tree.link_names.push_back(arm.link_names[static_cast<size_t>(k + 1)] + "_b");
    }
    for (int k = 0; k < 2 * m; ++k) tree.parents.push_back(k == 0 || k == m ? -1 : k - 1);
    auto twice = [](const Eigen::VectorXd& v) {
      Eigen::VectorXd w(2 * v.size());
      w << v, v;
      return w;
    };
    tree.inertial = twice(arm.inertial);
    tree.rotor_inertia = twice(arm.rotor_inertia);
    tree.viscous = twice(arm.viscous);
    tree.coulomb = twice(arm.coulomb);
    for (ParameterLayout layout : {ParameterLayout{false, false}, ParameterLayout{true, true}}) {
      BaseOptions opt;
      opt.layout = layout;
      const BaseParameters one = computeBaseParameters(arm, opt);
      const BaseParameters two = computeBaseParameters(tree, opt);
      const std::string what = tree.name + (layout.rotor ? " Ia+Fv+Fc" : "");
      const int nb = one.eom.size(), P = layout.size(m);
      ASSERT_EQ(two.eom.size(), 2 * nb) << what;
      auto relabel = [m](const std::string& name) {
        size_t d = name.size();
        while (d > 0 && std::isdigit(static_cast<unsigned char>(name[d - 1]))) --d;
        return name.substr(0, d) + std::to_string(std::stoi(name.substr(d)) + m);
      };
      const Eigen::MatrixXd Y1(one.eom.decision.Y);
      const Eigen::MatrixXd Y2(two.eom.decision.Y);
      for (int b = 0; b < nb; ++b) {
        EXPECT_EQ(two.eom.names[b], one.eom.names[b]) << what;
        EXPECT_EQ(two.eom.names[nb + b], relabel(one.eom.names[b])) << what;
      }
      // the same elimination on the same numbers: equal to rounding (1e-12 of Y's largest entry)
      const double tol = 1e-12 * std::max(1.0, Y1.cwiseAbs().maxCoeff());
      EXPECT_LE((Y2.topLeftCorner(nb, P) - Y1).cwiseAbs().maxCoeff(), tol) << what;
      EXPECT_LE((Y2.bottomRightCorner(nb, P) - Y1).cwiseAbs().maxCoeff(), tol) << what;
      EXPECT_TRUE(Y2.topRightCorner(nb, P).isZero(0.0)) << what;
      EXPECT_TRUE(Y2.bottomLeftCorner(nb, P).isZero(0.0)) << what;
      // The Lagrangian's constant is shared: independent check of its count.
      EXPECT_EQ(two.lagrangian.size(), test::sampledRank(tree, layout, 2 * P + 20, rng, true))
          << what;
      opt.method = BaseMethod::Numerical;
      const BaseParameters num = computeBaseParameters(tree, opt);
      EXPECT_EQ(two.eom.size(), num.eom.size()) << what;
      EXPECT_EQ(two.lagrangian.size(), num.lagrangian.size()) << what;
      expectTreeSetsReproduce(tree, two, rng, what);
    }
  }
}

TEST(BaseParameters, EchelonRejectsBadOrders) {
  const Eigen::MatrixXd Z = Eigen::MatrixXd::Identity(3, 3);
  EXPECT_THROW(echelon(Z, {0, 1}), std::invalid_argument);
  EXPECT_THROW(echelon(Z, {0, 1, 1}), std::invalid_argument);
  const RankDecision d = echelon(Z, {2, 0, 1});
  EXPECT_EQ(d.pivots, (std::vector<int>{2, 0, 1}));
}

// The formulas, written on request, evaluate to p_b = Y pi: their text carries the coefficients at
// full precision and the right names and signs.
TEST(BaseParameters, FormulasEvaluateToTheBaseValues) {
  std::mt19937 rng(7);
  BaseOptions opt;
  opt.layout = {true, true};
  const BaseParameters bp = computeBaseParameters(loadYaml(test::robotFile("puma560")), opt);
  const std::vector<std::string> text = bp.eom.formulas(bp.classical_names);
  ASSERT_EQ(static_cast<int>(text.size()), bp.eom.size());
  const Eigen::VectorXd pi = test::random(rng, static_cast<int>(bp.classical_names.size()));
  const Eigen::VectorXd pb = bp.values(pi);
  for (int b = 0; b < bp.eom.size(); ++b) {
    std::istringstream in(text[b]);
    std::string name, eq, token;
    in >> name >> eq;
    EXPECT_EQ(name, bp.eom.names[b]);
    double sum = 0.0, sign = 1.0;
    while (in >> token) {
      if (token == "+" || token == "-") {
        sign = token == "-" ? -1.0 : 1.0;
        continue;
      }
      if (token[0] == '-') {  // a leading minus is written on the first term
        sign = -1.0;
        token = token.substr(1);
      }
      const auto star = token.find('*');
      const double c = star == std::string::npos ? 1.0 : std::stod(token.substr(0, star));
      const std::string p = star == std::string::npos ? token : token.substr(star + 1);
      const auto it = std::find(bp.classical_names.begin(), bp.classical_names.end(), p);
      ASSERT_NE(it, bp.classical_names.end()) << text[b];
      sum += sign * c * pi[it - bp.classical_names.begin()];
      sign = 1.0;
    }
    EXPECT_NEAR(sum, pb[b], 1e-12 * std::max(1.0, std::abs(pb[b]))) << text[b];
  }
  EXPECT_THROW(bp.eom.formulas({"XX1"}), std::invalid_argument);
}
