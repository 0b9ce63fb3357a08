// The projection kernel and the echelon form against independent references: the coordinates Z
// evaluated on their basis functions reproduce the Lagrangian regressor computed by Newton-Euler
// (energyRegressors), and the elimination on small hand-made matrices gives the hand-derived
// pivots, regrouping matrix and formulas.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>

#include "mindyn/base_parameters.hpp"
#include "mindyn/projection.hpp"
#include "mindyn/urdf.hpp"
#include "test_util.hpp"
#include "tree_paths.hpp"

using namespace mindyn;

namespace {

// Value of basis function (l0; l1..ln) at (q, dq), from its definition (docs, section 3).
double basisValue(const BasisFunction& b, const Model& model, const Eigen::VectorXd& q,
                  const Eigen::VectorXd& dq) {
  double v = 1.0;
  if (b.l0 > 0) {
    const int i = static_cast<int>(std::floor((1 + std::sqrt(8.0 * b.l0 - 7)) / 2));
    const int j = b.l0 - i * (i - 1) / 2;
    v = i == j ? 0.5 * dq[i - 1] * dq[i - 1] : dq[i - 1] * dq[j - 1];
  }
  for (int k = 0; k < model.nq(); ++k) {
    const double x = q[k];
    if (model.joints[k].type == JointType::Revolute) {
      const double f[5] = {1.0, std::cos(x), std::sin(x), std::cos(2 * x), std::sin(2 * x)};
      v *= f[b.l[k] - 1];
    } else {
      const double f[3] = {1.0, x, x * x};
      v *= f[b.l[k] - 1];
    }
  }
  return v;
}

// A URDF chain with random origins, axes, joint types and inertias.
std::string randomUrdf(std::mt19937& rng, int n) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::ostringstream s;
  s.precision(17);
  s << "<robot name=\"random\"><link name=\"l0\"/>";
  for (int k = 1; k <= n; ++k) {
    const double m = 1.0 + 2.0 * std::abs(u(rng));
    s << "<link name=\"l" << k << "\"><inertial><origin xyz=\"" << 0.2 * u(rng) << ' '
      << 0.2 * u(rng) << ' ' << 0.2 * u(rng) << "\"/><mass value=\"" << m << "\"/>"
      << "<inertia ixx=\"0.05\" ixy=\"" << 0.01 * u(rng) << "\" ixz=\"" << 0.01 * u(rng)
      << "\" iyy=\"0.04\" iyz=\"" << 0.01 * u(rng) << "\" izz=\"0.03\"/></inertial></link>";
    Eigen::Vector3d axis(u(rng), u(rng), u(rng));
    axis.normalize();
    s << "<joint name=\"j" << k << "\" type=\"" << (k % 3 == 2 ? "prismatic" : "revolute")
      << "\"><parent link=\"l" << k - 1 << "\"/><child link=\"l" << k << "\"/><origin xyz=\""
      << 0.5 * u(rng) << ' ' << 0.5 * u(rng) << ' ' << 0.5 * u(rng) << "\" rpy=\"" << 3 * u(rng)
      << ' ' << 3 * u(rng) << ' ' << 3 * u(rng) << "\"/><axis xyz=\"" << axis.x() << ' ' << axis.y()
      << ' ' << axis.z()
      << "\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>";
  }
  s << "</robot>";
  return s.str();
}

void expectCoordinatesReproduceLagrangian(const Model& model, ParameterLayout layout,
                                          const std::string& what) {
  const InfluenceCoordinates ic = influenceCoordinates(model, layout);
  const int n = model.nq(), P = layout.size(n);
  ASSERT_EQ(ic.cols(), P) << what;
  Data data(model);
  Eigen::VectorXd wK(P), wP(P);
  std::mt19937 rng(7);
  for (int trial = 0; trial < 4; ++trial) {
    const Eigen::VectorXd q = test::random(rng, n, 2.0), dq = test::random(rng, n, 2.0);
    std::vector<double> phi(ic.rows());
    for (int r = 0; r < ic.rows(); ++r) phi[r] = basisValue(ic.basis(r), model, q, dq);
    Eigen::VectorXd w = Eigen::VectorXd::Zero(P);
    for (const auto& e : ic.entries) w[e.col] += phi[e.row] * e.value;
    // A tree's reference: the serial chains of its root paths.
    Eigen::VectorXd wL;
    if (model.isSerial()) {
      energyRegressors(model, data, q, dq, layout, wK, wP);
      wL = wK - wP;
    } else {
      wL = test::pathEnergyRegressor(model, q, dq, layout);
    }
    EXPECT_LE((w - wL).norm(), 1e-12 * std::max(1.0, wL.norm())) << what << " trial " << trial;
  }
}

}  // namespace

TEST(Projection, CoordinatesReproduceTheLagrangianRegressor) {
  for (const char* name : {"puma560", "zcr07s", "stanford", "puma560_3"}) {
    const Model model = loadYaml(test::robotFile(name));
    expectCoordinatesReproduceLagrangian(model, {}, name);
    expectCoordinatesReproduceLagrangian(model, {true, false}, std::string(name) + " with Ia");
  }
  expectCoordinatesReproduceLagrangian(planarArm(4, true), {}, "planar4");
  expectCoordinatesReproduceLagrangian(planarArm(3, false), {true, false}, "planar3h");
}

TEST(Projection, CoordinatesOfRandomChains) {
  std::mt19937 rng(11);
  for (int n = 2; n <= 5; ++n) {
    const Model model = parseUrdf(randomUrdf(rng, n), "", "random");
    ASSERT_EQ(model.nq(), n);
    expectCoordinatesReproduceLagrangian(model, {true, false},
                                         "random chain n=" + std::to_string(n));
  }
}

// On a tree, each row's basis function involves the joints of one root path only (the joints
// of q and dq all support the deepest one, whose 1-based index is depth()), no two rows have the
// same basis function, the row's coordinates lie on the links that deepest joint carries, and Z
// reproduces the Lagrangian regressor of the serial chains of the root paths.
TEST(Projection, CoordinatesOfRandomTrees) {
  std::mt19937 rng(23);
  for (const Model& model : test::testTrees(rng)) {
    const int n = model.nq();
    const ParameterLayout layout{n % 2 == 0, false};
    const std::string& what = model.name;
    const InfluenceCoordinates ic = influenceCoordinates(model, layout);
    std::vector<std::uint64_t> keys = ic.keys;
    std::sort(keys.begin(), keys.end());
    EXPECT_EQ(std::adjacent_find(keys.begin(), keys.end()), keys.end()) << what;
    // Counted, the first offence shown: a wrong recursion offends on thousands of rows.
    int off_path = 0, wrong_depth = 0, off_subtree = 0;
    std::string first;
    std::vector<int> deepest(ic.rows(), -1);
    for (int r = 0; r < ic.rows(); ++r) {
      const BasisFunction b = ic.basis(r);
      std::vector<int> joints;
      if (b.l0 > 0) {
        const int i = static_cast<int>(std::floor((1 + std::sqrt(8.0 * b.l0 - 7)) / 2));
        joints = {i - 1, b.l0 - i * (i - 1) / 2 - 1};
      }
      for (int k = 0; k < n; ++k)
        if (b.l[k] > 1) joints.push_back(k);
      const int d = joints.empty() ? -1 : *std::max_element(joints.begin(), joints.end());
      bool bad = false;
      for (int j : joints) bad = bad || !model.supports(j, d);
      off_path += bad;
      wrong_depth += ic.depth(r) != d + 1;
      if ((bad || ic.depth(r) != d + 1) && first.empty()) first = b.toString(model);
      deepest[r] = d;
    }
    for (const auto& e : ic.entries) {
      const int link = e.col / layout.perLink(), d = deepest[e.row];
      if (d >= 0 && !model.supports(d, link)) {
        ++off_subtree;
        if (first.empty())
          first = ic.basis(e.row).toString(model) + " column " + std::to_string(e.col);
      }
    }
    EXPECT_EQ(off_path + wrong_depth + off_subtree, 0)
        << what << ": " << off_path << " rows off one root path, " << wrong_depth
        << " with a wrong depth, " << off_subtree
        << " coordinates off the deepest joint's subtree; first: " << first;
    expectCoordinatesReproduceLagrangian(model, layout, what);
  }
}

// The cost counted before the recursion bounds what the recursion then forms.
TEST(Projection, CostEstimateBoundsTheRecursion) {
  auto check = [](const Model& model, ParameterLayout layout, const std::string& what) {
    const ProjectionCost c = projectionCost(model, layout);
    const InfluenceCoordinates ic = influenceCoordinates(model, layout);
    EXPECT_GE(c.terms, ic.terms_formed) << what;
    EXPECT_GE(c.rows, ic.rows()) << what;
    EXPECT_GE(c.entries, static_cast<double>(ic.entries.size())) << what;
    EXPECT_GT(c.bytes, 0.0) << what;
  };
  for (const char* name : {"puma560", "stanford", "zcr07s"}) {
    const Model model = loadYaml(test::robotFile(name));
    check(model, {}, name);
    check(model, {true, false}, std::string(name) + " with Ia");
  }
  check(planarArm(7, true), {}, "planar7");
  std::mt19937 rng(5);
  for (int n = 2; n <= 6; ++n)
    check(parseUrdf(randomUrdf(rng, n), "", "random"), {true, false},
          "random chain n=" + std::to_string(n));
  check(planarArm(5, false), {true, false}, "planar5h");
  for (const Model& tree : test::testTrees(rng)) check(tree, {true, false}, tree.name);
}

TEST(Projection, OverBudgetIsRefusedBeforeComputing) {
  const Model model = planarArm(6, true);
  const ProjectionCost c = projectionCost(model);
  try {
    influenceCoordinates(model, {}, c.bytes / 2);
    FAIL() << "not refused";
  } catch (const ModelError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("6-joint chain"), std::string::npos) << msg;
    EXPECT_NE(msg.find("method='numerical'"), std::string::npos) << msg;
  }
  EXPECT_NO_THROW(influenceCoordinates(model, {}, c.bytes));
  BaseOptions o;
  o.projection_budget = c.bytes / 2;
  EXPECT_THROW(computeBaseParameters(model, o), ModelError);
  std::mt19937 rng(3);
  const Model tree = test::randomChain(rng, 5, false, false, true);
  ASSERT_FALSE(tree.isSerial());
  try {
    influenceCoordinates(tree, {}, projectionCost(tree).bytes / 2);
    FAIL() << "not refused";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("5-joint tree"), std::string::npos) << e.what();
  }
}

// A tree may have more joints than a serial chain, not longer root paths (the packed index).
TEST(Projection, LongRootPathsOfATreeAreRefused) {
  std::mt19937 rng(9);
  Model tree = test::randomChain(rng, 18, false, true);
  tree.parents = {-1};
  for (int k = 1; k < 17; ++k) tree.parents.push_back(k - 1);  // a 17-joint path
  tree.parents.push_back(0);
  try {
    influenceCoordinates(tree);
    FAIL() << "not refused";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("root paths of up to 16 joints on a tree, the longest of "
                                         "this 18-joint tree has 17"),
              std::string::npos)
        << e.what();
  }
  tree.parents[16] = 0;  // 16 at most: accepted, then refused for its size (17 general axes)
  try {
    influenceCoordinates(tree);
    FAIL() << "not refused";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("over its budget"), std::string::npos) << e.what();
  }
}

TEST(Projection, BasisIndexRoundTrip) {
  // l0 = J(4, 3) = 4 * 3 / 2 + 3 = 9: the product dq3 dq4
  const std::vector<int> l = {1, 5, 3, 2, 4, 1};
  const BasisFunction b = unpackBasis(packBasis(9, l), 6);
  EXPECT_EQ(b.l0, 9);
  EXPECT_EQ(b.l, l);
  EXPECT_EQ(b.toString(planarArm(6)), "dq3*dq4*sin(2q2)*sin(q3)*cos(q4)*cos(2q5)");
}

TEST(Echelon, HandMadeDependencies) {
  // columns: a, 2a, b, a - b, 0, c: pivots a, b, c; 2a = 2 * a; a - b = a - b; column 4 no effect
  Eigen::MatrixXd Z(4, 6);
  Z << 1, 2, 0, 1, 0, 3,  //
      2, 4, 1, 1, 0, 0,   //
      0, 0, 5, -5, 0, 1,  //
      1, 2, 1, 0, 0, 2;
  const RankDecision d = echelon(Z, {0, 1, 2, 3, 4, 5});
  EXPECT_EQ(d.pivots, (std::vector<int>{0, 2, 5}));
  EXPECT_EQ(d.dependent, (std::vector<int>{1, 3}));
  EXPECT_EQ(d.zero, (std::vector<int>{4}));
  Eigen::MatrixXd Y(3, 6);
  Y << 1, 2, 0, 1, 0, 0,  //
      0, 0, 1, -1, 0, 0,  //
      0, 0, 0, 0, 0, 1;
  const Eigen::MatrixXd dY(d.Y);
  EXPECT_LT((dY - Y).cwiseAbs().maxCoeff(), 1e-14);
  for (int i = 0; i < Y.size(); ++i)  // 0 and +-1 are recognised exactly
    if (Y.data()[i] == 0.0 || std::abs(Y.data()[i]) == 1.0) {
      EXPECT_EQ(dY.data()[i], Y.data()[i]) << "entry " << i;
    }
  EXPECT_LT(d.largest_dropped, 1e-15);
  EXPECT_FALSE(d.near_degenerate);

  // another order keeps other columns: a - b, then 2a; a = 0.5 (2a), b = 0.5 (2a) - (a - b)
  const RankDecision e = echelon(Z, {3, 1, 0, 2, 4, 5});
  EXPECT_EQ(e.pivots, (std::vector<int>{3, 1, 5}));
  const Eigen::MatrixXd eY(e.Y);
  EXPECT_NEAR(eY(1, 0), 0.5, 1e-15);
  const std::vector<std::string> names = {"A", "B", "C", "D", "E", "F"};
  EXPECT_EQ(formatFormula("BR", eY.row(1), names), "BR = 0.5*A + B + 0.5*C");
  EXPECT_EQ(formatFormula("DR", eY.row(0), names), "DR = -C + D");
  EXPECT_THROW(echelon(Z, {0, 1, 2}), std::invalid_argument);
  EXPECT_THROW(echelon(Z, {0, 0, 1, 2, 3, 4}), std::invalid_argument);
}

TEST(Echelon, NearDegenerateIsFlagged) {
  // column 2 = column 0 + 1e-11 * e: kept at tolerance 1e-12, dropped at 1e-9
  Eigen::MatrixXd Z(3, 3);
  Z << 1, 0, 1, 0, 1, 0, 0, 0, 1e-11;
  const RankDecision d = echelon(Z, {0, 1, 2});
  EXPECT_EQ(d.rank(), 2);
  EXPECT_NEAR(d.largest_dropped, 1e-11, 1e-13);
  EXPECT_TRUE(d.near_degenerate);
  EXPECT_EQ(d.rank_tighter, 3);
  EXPECT_EQ(echelon(Z, {0, 1, 2}, 1e-12).rank(), 3);
}

TEST(Echelon, ARowAllOfATiltsSizeIsMeasuredAgainstTheLargestRow) {
  // Row 1 holds only column 1, at 1e-11: full-size against itself, 1e-11 of the largest row.
  Eigen::MatrixXd Z(2, 2);
  Z << 1, 0, 0, 1e-11;
  const RankDecision d = echelon(Z, {0, 1});
  EXPECT_EQ(d.rank(), 1);
  EXPECT_TRUE(d.near_degenerate);
  EXPECT_EQ(d.rank_tighter, 2);  // at 1e-12, the rows as they are
  EXPECT_EQ(d.undecided, (std::vector<int>{1}));
  // At 1e-12 against the largest row it is kept; without a scale (rows that are directions,
  // each normalised) it is full-size; against a given scale of 1e-10, a tenth of it.
  EXPECT_EQ(echelon(Z, {0, 1}, 1e-12).rank(), 2);
  EXPECT_EQ(echelon(Z, {0, 1}, 1e-9, {}, {}, -1.0).rank(), 2);
  EXPECT_EQ(echelon(Z, {0, 1}, 1e-9, {}, {}, 1e-10).rank(), 2);
  EXPECT_EQ(echelon(Z, {0, 1}, 1e-9, {}, {}, 1e-1).rank(), 1);
  EXPECT_EQ(largestRow(Eigen::SparseMatrix<double>(Z.sparseView()), Eigen::Vector2d(1.0, 2.0)),
            1.0);
  EXPECT_THROW(echelon(Z, {0, 1}, 1e-9, {}, {}, std::nan("")), std::invalid_argument);
  // The other decision, far from both neighbouring tolerances, affects nothing.
  EXPECT_TRUE(echelon(Eigen::MatrixXd::Identity(2, 2), {0, 1}).undecided.empty());
}

TEST(Echelon, KhalilOrder) {
  const std::vector<int> o = khalilOrder(2, {true, true});
  // link 1: XX XY XZ YZ ZZ MX MY, YY MZ M, Ia, Fv, Fc; then link 2 (13 columns per link)
  const std::vector<int> first = {0, 1, 2, 4, 5, 6, 7, 3, 8, 9, 10, 11, 12};
  ASSERT_EQ(o.size(), 26u);
  EXPECT_EQ(std::vector<int>(o.begin(), o.begin() + 13), first);
  for (int i = 0; i < 13; ++i) EXPECT_EQ(o[13 + i], first[i] + 13);
}
