// The IK solver's own chain kinematics against KDL (pose, Jacobian) and finite differences; the
// solver on reachable targets (answers checked with KDL's forward kinematics and the limits), on
// unreachable and invalid targets.
#include <gtest/gtest.h>

#include <kdl/frames.hpp>

#include "mindyn/ik.hpp"
#include "mindyn/kinematics.hpp"
#include "mindyn/spatial.hpp"
#include "mindyn/urdf.hpp"
#include "test_util.hpp"

using namespace mindyn;
using mindyn::test::random;

namespace {

std::vector<std::pair<std::string, Model>> robots() {
  std::vector<std::pair<std::string, Model>> out;
  for (const char* name : {"puma560", "zcr07s", "stanford"})
    out.emplace_back(name, loadYaml(test::robotFile(name)));
  out.emplace_back("planar3", planarArm(3));
  const std::string dir = MINDYN_ROBOT_DATA_DIR;
  if (dir.empty()) {
    ADD_FAILURE() << "MINDYN_ROBOT_DATA_DIR is not set";
    return out;
  }
  out.emplace_back("ur5", loadUrdf(dir + "/ur_description/urdf/ur5_robot.urdf", "tool0"));
  out.emplace_back("panda", loadUrdf(dir + "/panda_description/urdf/panda.urdf", "panda_hand"));
  return out;
}

Eigen::VectorXd insideLimits(const Model& model, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::VectorXd q(model.nq());
  for (int k = 0; k < model.nq(); ++k) {
    const JointLimits& l = model.joints[k].limits;
    const double lo = std::isfinite(l.lower) ? l.lower : -M_PI;
    const double hi = std::isfinite(l.upper) ? l.upper : M_PI;
    q[k] = lo + (hi - lo) * u(rng);
  }
  return q;
}

bool insideModelLimits(const Model& model, const Eigen::VectorXd& q) {
  for (int k = 0; k < model.nq(); ++k) {
    const JointLimits& l = model.joints[k].limits;
    if (std::isfinite(l.lower) && q[k] < l.lower) return false;
    if (std::isfinite(l.upper) && q[k] > l.upper) return false;
  }
  return true;
}

// KDL's twist between two frames (diff), max |component|.
double kdlPoseError(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  const KDL::Twist t = KDL::diff(toKdl(a), toKdl(b));
  double m = 0;
  for (int i = 0; i < 6; ++i) m = std::max(m, std::abs(t[i]));
  return m;
}

}  // namespace

TEST(Ik, ChainKinematicsMatchesKdl) {
  std::mt19937 rng(31);
  for (auto& [name, model] : robots()) {
    ChainKinematics chain(model);
    Kinematics kdl(model);
    const int n = model.nq();
    Matrix6Xd J(6, n);
    Eigen::Isometry3d T, T2;
    for (int trial = 0; trial < 10; ++trial) {
      const Eigen::VectorXd q = random(rng, n, 3);
      chain.poseAndJacobian(q, T, J);
      chain.pose(q, T2);
      EXPECT_LT((T.matrix() - kdl.pose(q).matrix()).norm(), 1e-12) << name;
      EXPECT_LT((T2.matrix() - T.matrix()).norm(), 1e-14) << name;
      EXPECT_LT((J - kdl.jacobian(q)).norm(), 1e-12) << name;
    }
  }
}

TEST(Ik, PoseErrorIsKdlsTwistDiffAndFirstOrder) {
  std::mt19937 rng(32);
  const Model model = loadYaml(test::robotFile("puma560"));
  ChainKinematics chain(model);
  Eigen::Matrix<double, 6, 1> e;
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::Isometry3d A, B;
    chain.pose(random(rng, 6, 3), A);
    chain.pose(random(rng, 6, 3), B);
    const double m = poseError(A, B, e);
    const KDL::Twist t = KDL::diff(toKdl(A), toKdl(B));
    for (int i = 0; i < 6; ++i) EXPECT_NEAR(e[i], t[i], 1e-9);
    EXPECT_DOUBLE_EQ(m, e.cwiseAbs().maxCoeff());
  }
  // rotations by nearly pi keep the right axis and angle
  for (double angle : {M_PI - 1e-9, M_PI, M_PI - 1e-4}) {
    const Eigen::Vector3d axis = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
    Eigen::Isometry3d A = Eigen::Isometry3d::Identity(), B = Eigen::Isometry3d::Identity();
    B.linear() = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
    poseError(A, B, e);
    EXPECT_LT((e.tail<3>() - angle * axis).norm(), 1e-6) << angle;
  }
}

TEST(Ik, SolvesReachableTargetsInsideTheLimits) {
  std::mt19937 rng(33);
  for (auto& [name, model] : robots()) {
    IkOptions options;
    options.max_time = 0;  // attempts bound the work; no dependence on the machine's load
    IkSolver solver(model, options);
    Kinematics kdl(model);
    const int n = model.nq();
    const Eigen::VectorXd mid = 0.5 * (solver.lower() + solver.upper());
    Eigen::VectorXd q(n);
    int solved = 0;
    const int trials = 50;
    for (int trial = 0; trial < trials; ++trial) {
      const Eigen::VectorXd qt = insideLimits(model, rng);
      const Eigen::Isometry3d target = kdl.pose(qt);
      const IkResult r = solver.solve(target, mid, q);
      if (!r.success()) continue;
      ++solved;
      EXPECT_LE(kdlPoseError(kdl.pose(q), target), 1.0001e-5) << name;
      EXPECT_LE(r.error, 1e-5);
      EXPECT_TRUE(insideModelLimits(model, q)) << name << ": " << q.transpose();
    }
    // the planar arm reaches only poses in its plane: all of these are such poses
    EXPECT_GE(solved, trials - 1) << name;
  }
}

TEST(Ik, ReportsUnreachableAndInvalidTargets) {
  const Model model = loadYaml(test::robotFile("puma560"));
  IkOptions options;
  options.max_time = 0.02;
  IkSolver solver(model, options);
  Eigen::VectorXd q(6);
  const Eigen::VectorXd q0 = Eigen::VectorXd::Zero(6);
  Eigen::Isometry3d far = Eigen::Isometry3d::Identity();
  far.translation() << 5.0, 0.0, 0.0;  // beyond the reach of the arm
  IkResult r = solver.solve(far, q0, q);
  EXPECT_FALSE(r.success());
  EXPECT_TRUE(r.status == IkStatus::NotConverged || r.status == IkStatus::Timeout);
  EXPECT_GT(r.error, 1.0);
  EXPECT_TRUE(q.allFinite());

  Eigen::Isometry3d bad = Eigen::Isometry3d::Identity();
  bad.linear() << 1, 0, 0, 0, 2, 0, 0, 0, 1;
  r = solver.solve(bad, q0, q);
  EXPECT_EQ(r.status, IkStatus::InvalidTarget);
  EXPECT_STREQ(toString(r.status), "invalid target");
  bad.translation()[0] = std::nan("");
  EXPECT_EQ(solver.solve(bad, q0, q).status, IkStatus::InvalidTarget);
}

TEST(Ik, StartOutsideTheLimitsIsBroughtInside) {
  // a revolute joint given 2 pi too far, and one beyond its limit
  const Model model = loadYaml(test::robotFile("zcr07s"));
  IkSolver solver(model);
  Kinematics kdl(model);
  Eigen::VectorXd qt(6), q(6);
  qt << 0.3, 0.5, 0.8, -0.4, 0.6, 1.0;
  Eigen::VectorXd q0 = qt;
  q0[0] += 2 * M_PI;
  q0[1] = 3.0;  // limit 90 deg
  const IkResult r = solver.solve(kdl.pose(qt), q0, q);
  EXPECT_TRUE(r.success());
  EXPECT_TRUE(insideModelLimits(model, q));
}

TEST(Ik, ChainKinematicsOfATreeFollowsTheLastLinksRootPath) {
  // Central differences of the tool pose: the Jacobian's columns, zero for joints of other
  // branches.
  std::mt19937 rng(5);
  for (int trial = 0; trial < 4; ++trial) {
    const Model tree = test::randomTree(rng, 8, trial % 2 == 0);
    ChainKinematics kin(tree);
    const int n = tree.nq();
    const Eigen::VectorXd q = test::random(rng, n, 2);
    Eigen::Isometry3d T, Tp, Tm;
    Matrix6Xd J(6, n);
    kin.poseAndJacobian(q, T, J);
    const double h = 1e-6;
    for (int k = 0; k < n; ++k) {
      Eigen::VectorXd qp = q, qm = q;
      qp[k] += h;
      qm[k] -= h;
      kin.pose(qp, Tp);
      kin.pose(qm, Tm);
      const Eigen::AngleAxisd turn(Tp.linear() * Tm.linear().transpose());
      Vector6d fd;
      fd.head<3>() = (Tp.translation() - Tm.translation()) / (2 * h);
      fd.tail<3>() = turn.angle() * turn.axis() / (2 * h);
      EXPECT_LT((J.col(k) - fd).norm(), 1e-7 * std::max(1.0, fd.norm())) << "joint " << k;
      if (!tree.supports(k, n - 1)) {
        EXPECT_EQ(J.col(k).norm(), 0.0) << "joint " << k;
      }
    }
  }
}
