// Base parameters reproduce the torques (W_b Y pi = W pi, and through the classical algorithm
// with the embedded base vector) and agree in number with the numerical method.
#include <gtest/gtest.h>

#include <algorithm>
#include <sstream>

#include "mindyn/base_parameters.hpp"
#include "mindyn/projection.hpp"
#include "mindyn/urdf.hpp"
#include "test_util.hpp"

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
