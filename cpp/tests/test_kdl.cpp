// Inverse dynamics and kinematics against Orocos KDL (ChainIdSolver_RNE, FK and Jacobian
// solvers), on the bundled robots and on URDFs of example-robot-data.
#include <gtest/gtest.h>

#include <filesystem>
#include <kdl/chainidsolver_recursive_newton_euler.hpp>

#include "mindyn/dynamics.hpp"
#include "mindyn/kinematics.hpp"
#include "mindyn/urdf.hpp"
#include "test_util.hpp"

using namespace mindyn;
using mindyn::test::random;
using mindyn::test::relErr;

namespace {

std::vector<std::pair<std::string, Model>> robots() {
  std::vector<std::pair<std::string, Model>> out;
  for (const char* name : {"puma560", "puma560_3", "zcr07s", "stanford"})
    out.emplace_back(name, loadYaml(test::robotFile(name)));
  out.emplace_back("planar5", planarArm(5));
  const std::string dir = MINDYN_ROBOT_DATA_DIR;
  if (dir.empty()) {
    ADD_FAILURE() << "MINDYN_ROBOT_DATA_DIR is not set: configure with "
                     "-DMINDYN_ROBOT_DATA_DIR=<example-robot-data>/robots";
    return out;
  }
  out.emplace_back("ur5", loadUrdf(dir + "/ur_description/urdf/ur5_robot.urdf"));
  out.emplace_back("panda", loadUrdf(dir + "/panda_description/urdf/panda.urdf", "panda_link8"));
  return out;
}

KDL::JntArray toJnt(const Eigen::VectorXd& v) {
  KDL::JntArray a(v.size());
  a.data = v;
  return a;
}

}  // namespace

TEST(Kdl, InverseDynamicsMatchesChainIdSolverRNE) {
  std::mt19937 rng(11);
  for (const auto& [name, model] : robots()) {
    const int n = model.nq();
    Data data(model);
    const KDL::Chain chain = toKdlChain(model);
    const Eigen::Vector3d g = model.gravity;
    KDL::ChainIdSolver_RNE kdl(chain, KDL::Vector(g.x(), g.y(), g.z()));
    KDL::Wrenches wrenches(chain.getNrOfSegments(), KDL::Wrench::Zero());
    KDL::JntArray tk(n);
    Eigen::VectorXd tau(n);
    double worst = 0;
    for (int trial = 0; trial < 50; ++trial) {
      const Eigen::VectorXd q = random(rng, n, 3), dq = random(rng, n, 2), ddq = random(rng, n, 4);
      inverseDynamics(model, data, q, dq, ddq, model.parameters(), {}, tau);
      ASSERT_GE(kdl.CartToJnt(toJnt(q), toJnt(dq), toJnt(ddq), wrenches, tk), 0) << name;
      worst = std::max(worst, relErr(tau, tk.data));
    }
    EXPECT_LT(worst, 1e-10) << name;
  }
}

TEST(Kdl, PosesMatchTheModelsJointTransforms) {
  std::mt19937 rng(12);
  for (const auto& [name, model] : robots()) {
    Kinematics kin(model);
    const int n = model.nq();
    for (int trial = 0; trial < 10; ++trial) {
      const Eigen::VectorXd q = random(rng, n, 3);
      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
      for (int k = 0; k < n; ++k) {
        T = T * model.joints[k].transform(q[k]);
        EXPECT_LT((kin.pose(q, k).matrix() - T.matrix()).norm(), 1e-12) << name << " link " << k;
      }
      EXPECT_LT((kin.pose(q).matrix() - (T * model.tool).matrix()).norm(), 1e-12) << name;
    }
  }
}

TEST(Kdl, JacobianMatchesFiniteDifferencesOfThePose) {
  std::mt19937 rng(13);
  for (const auto& [name, model] : robots()) {
    Kinematics kin(model);
    const int n = model.nq();
    const Eigen::VectorXd q = random(rng, n, 2);
    const auto J = kin.jacobian(q);
    const double h = 1e-6;
    for (int k = 0; k < n; ++k) {
      Eigen::VectorXd qp = q, qm = q;
      qp[k] += h;
      qm[k] -= h;
      const Eigen::Isometry3d Tp = kin.pose(qp), Tm = kin.pose(qm);
      const Eigen::Vector3d v = (Tp.translation() - Tm.translation()) / (2 * h);
      const Eigen::Matrix3d dR = (Tp.linear() - Tm.linear()) / (2 * h);
      const Eigen::Matrix3d W = dR * kin.pose(q).linear().transpose();  // skew(omega)
      const Eigen::Vector3d w(W(2, 1), W(0, 2), W(1, 0));
      EXPECT_LT((J.col(k).head<3>() - v).norm(), 1e-7) << name << " joint " << k;
      EXPECT_LT((J.col(k).tail<3>() - w).norm(), 1e-7) << name << " joint " << k;
    }
  }
}
