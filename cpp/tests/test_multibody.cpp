// The multibody algorithms (multi-DOF joints, floating bases): on single-DOF models they give
// what the single-DOF dynamics give (those are checked against Pinocchio and KDL elsewhere); on
// a model with every joint kind the regressor, the mass matrix, the kinetic energy and forward
// dynamics agree with inverse dynamics. The comparison with Pinocchio itself is in
// tests/test_multibody.py, the allocation test in test_realtime.cpp.
#include <gtest/gtest.h>

#include <cmath>

#include "mindyn/description.hpp"
#include "mindyn/multibody.hpp"
#include "test_util.hpp"

using namespace mindyn;

TEST(Multibody, SingleDofModelsGiveTheSingleDofDynamics) {
  for (const auto& [name, model] : test::chainsAndTrees()) {
    Data data(model);
    MultibodyData mb(model);
    const int n = model.nq();
    const ParameterLayout layout;
    const Eigen::VectorXd pi = model.parameters(layout);
    std::mt19937 rng(3);
    const Eigen::VectorXd q = test::random(rng, n), dq = test::random(rng, n),
                          ddq = test::random(rng, n);
    Eigen::VectorXd t1(n), t2(n), a1(n), a2(n);
    Eigen::MatrixXd W1(n, 10 * n), W2(n, 10 * n), M1(n, n), M2(n, n);
    inverseDynamics(model, data, q, dq, ddq, pi, layout, t1);
    inverseDynamics(model, mb, q, dq, ddq, pi, t2);
    regressor(model, data, q, dq, ddq, layout, W1);
    regressor(model, mb, q, dq, ddq, W2);
    massMatrix(model, data, q, pi, layout, M1);
    massMatrix(model, mb, q, pi, M2);
    ASSERT_TRUE(forwardDynamics(model, data, q, dq, t1, pi, layout, a1));
    ASSERT_TRUE(forwardDynamics(model, mb, q, dq, t1, pi, a2));
    EXPECT_LE((t1 - t2).norm(), 1e-12 * t1.norm()) << name;
    EXPECT_LE((W1 - W2).norm(), 1e-12 * W1.norm()) << name;
    EXPECT_LE((M1 - M2).norm(), 1e-12 * M1.norm()) << name;
    EXPECT_LE((a1 - a2).norm(), 1e-9 * a1.norm()) << name;
    EXPECT_NEAR(kineticEnergy(model, data, q, dq, pi, layout), kineticEnergy(model, mb, q, dq, pi),
                1e-12 * std::abs(kineticEnergy(model, mb, q, dq, pi)) + 1e-300);
  }
}

TEST(Multibody, EveryKindIsConsistent) {
  const Model model = test::everyJointKind();
  ASSERT_EQ(model.configSize(), 7 + 4 + 2 + 2 + 4 + 1 + 1);
  ASSERT_EQ(model.velocitySize(), 6 + 3 + 2 + 2 + 3 + 1 + 1);
  MultibodyData data(model);
  const int nv = model.velocitySize(), n = model.nq();
  std::mt19937 rng(9);
  Eigen::VectorXd q(model.configSize());
  randomConfiguration(model, rng, q);
  const Eigen::VectorXd v = test::random(rng, nv), a = test::random(rng, nv);
  const Eigen::VectorXd& pi = model.inertial;
  Eigen::VectorXd tau(nv), g(nv), b(nv);
  Eigen::MatrixXd W(nv, 10 * n), M(nv, nv);
  inverseDynamics(model, data, q, v, a, pi, tau);
  regressor(model, data, q, v, a, W);
  EXPECT_LE((W * pi - tau).norm(), 1e-12 * tau.norm());
  massMatrix(model, data, q, pi, M);
  inverseDynamics(model, data, q, v, Eigen::VectorXd::Zero(nv), pi, b);
  EXPECT_LE((M * a + b - tau).norm(), 1e-12 * tau.norm());
  EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(M).info(), Eigen::Success);  // positive definite
  EXPECT_LE(std::abs(2 * kineticEnergy(model, data, q, v, pi) - v.dot(M * v)),
            1e-12 * v.dot(M * v));
  // Slotine-Li: Y(q, v, v, a) = the regressor; C(q, v) v = b(q, v)
  Eigen::MatrixXd Y(nv, 10 * n), C(nv, nv);
  slotineLiRegressor(model, data, q, v, v, a, Y);
  EXPECT_LE((Y - W).norm(), 1e-12 * W.norm());
  coriolisMatrix(model, data, q, v, pi, C);
  inverseDynamics(model, data, q, Eigen::VectorXd::Zero(nv), Eigen::VectorXd::Zero(nv), pi, g);
  EXPECT_LE((C * v + g - b).norm(), 1e-12 * b.norm());
  Eigen::VectorXd a2(nv);
  ASSERT_TRUE(forwardDynamics(model, data, q, v, tau, pi, a2));
  EXPECT_LE((a2 - a).norm(), 1e-9 * a.norm());
}

// The frame Jacobian times v is the velocity of the frame that the recursive velocity pass gives
// (link k's (angular; linear) velocity in its own axes, carried to the frame's origin), in the
// frame's axes (Local) and in the base's (LocalWorldAligned).
TEST(Multibody, TheFrameJacobianGivesTheVelocityOfTheRecursivePass) {
  const Model model = test::everyJointKind();
  MultibodyData data(model);
  const int nv = model.velocitySize();
  std::mt19937 rng(5);
  Eigen::VectorXd q(model.configSize());
  randomConfiguration(model, rng, q);
  const Eigen::VectorXd v = test::random(rng, nv);
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  X.translation() << 0.2, -0.1, 0.3;
  Eigen::MatrixXd J(6, nv), Jw(6, nv);
  kineticEnergy(model, data, q, v, model.inertial);  // leaves the link velocities in data.v
  const std::vector<Vector6d> vk = data.v;
  for (int k = 0; k < model.nq(); ++k) {
    const Eigen::Vector3d w = vk[k].head<3>(), o = vk[k].tail<3>() + w.cross(X.translation());
    Vector6d local;
    local << X.linear().transpose() * o, X.linear().transpose() * w;
    frameJacobian(model, data, q, k, X, ReferenceFrame::Local, J);
    frameJacobian(model, data, q, k, X, ReferenceFrame::LocalWorldAligned, Jw);
    EXPECT_LE((J * v - local).norm(), 1e-13 * local.norm()) << k;
    const Eigen::Matrix3d R = data.R0[k] * X.linear();
    Vector6d world;
    world << R * local.head<3>(), R * local.tail<3>();
    EXPECT_LE((Jw * v - world).norm(), 1e-13 * world.norm()) << k;
    for (int c = 0; c < nv; ++c) {  // the columns of joints off the path to link k are zero
      int j = 0;
      while (j + 1 < model.nq() && data.iv[j + 1] <= c) ++j;
      bool on_path = false;
      for (int i = k; i >= 0; i = model.parent(i)) on_path = on_path || i == j;
      if (!on_path) {
        EXPECT_EQ(J.col(c).norm(), 0.0) << k << " " << c;
      }
    }
  }
}

TEST(Multibody, MultiDofModelsAreRefusedByTheSingleDofAlgorithms) {
  const Model model = test::everyJointKind();
  try {
    Data data(model);
    FAIL() << "Data accepted a multi-DOF model";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("the floating joint 'fly'"), std::string::npos)
        << e.what();
  }
}

TEST(Multibody, ConfigurationNormsAreChecked) {
  const Model model = test::everyJointKind();
  std::mt19937 rng(2);
  Eigen::VectorXd q(model.configSize());
  randomConfiguration(model, rng, q);
  checkConfiguration(model, q);
  q[7] *= 1.01;  // the spherical joint's quaternion
  try {
    checkConfiguration(model, q);
    FAIL() << "a non-unit quaternion was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("spherical joint 'ball'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(checkMultibodySizes(model, q.size(), 3, -1, -1), std::invalid_argument);
}

// The single-DOF expansion of every kind (expandToSingleDof): at the configuration of the pairs
// that the factors' coordinates give (Z-Y-X angles to a quaternion, the planar angle to its
// cosine and sine), every real link has the same pose in the base frame, and the potential
// energies agree (the added links are massless).
TEST(Multibody, TheSingleDofExpansionMovesEveryRealLinkAsThePairs) {
  const Model model = test::everyJointKind();
  const SingleDofExpansion ex = expandToSingleDof(model);
  const Model& e = ex.model;
  ASSERT_TRUE(e.singleDof());
  EXPECT_EQ(e.nq(), 6 + 3 + 2 + 2 + 3 + 1 + 1);
  ASSERT_EQ(static_cast<int>(ex.column.size()), 10 * model.nq());
  for (int c = 0; c < 10 * model.nq(); ++c) EXPECT_EQ(e.inertial[ex.column[c]], model.inertial[c]);
  EXPECT_EQ(e.inertial.sum(), model.inertial.sum());  // the others are zero
  MultibodyData dm(model), de(e);
  std::mt19937 rng(4);
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::VectorXd th = 2.0 * test::random(rng, e.nq());
    Eigen::VectorXd q(model.configSize());
    auto zyx = [&](int i, double* out) {
      const Eigen::Quaterniond r(Eigen::AngleAxisd(th[i], Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(th[i + 1], Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(th[i + 2], Eigen::Vector3d::UnitX()));
      out[0] = r.x(), out[1] = r.y(), out[2] = r.z(), out[3] = r.w();
    };
    int i = 0, iq = 0;  // first factor, first q entry of each pair
    for (const Joint& j : model.joints) {
      double* out = q.data() + iq;
      switch (j.type) {
        case JointType::Spherical:
          zyx(i, out);
          i += 3;
          break;
        case JointType::Planar:
          out[0] = th[i], out[1] = th[i + 1], out[2] = std::cos(th[i + 2]);
          out[3] = std::sin(th[i + 2]);
          i += 3;
          break;
        case JointType::FreeFlyer:
          out[0] = th[i], out[1] = th[i + 1], out[2] = th[i + 2];
          zyx(i + 3, out + 3);
          i += 6;
          break;
        default:  // revolute, prismatic, universal, cylindrical: the factors' coordinates
          for (int f = 0; f < j.nq(); ++f) out[f] = th[i++];
      }
      iq += j.nq();
    }
    ASSERT_EQ(i, e.nq());
    forwardKinematics(model, dm, q);
    forwardKinematics(e, de, th);
    for (int k = 0, f = 0; f < e.nq(); ++f) {
      if (ex.link[f] < 0) continue;
      ASSERT_EQ(ex.link[f], k);
      EXPECT_LE((dm.R0[k] - de.R0[f]).norm(), 1e-12) << model.joints[k].name;
      EXPECT_LE((dm.p0[k] - de.p0[f]).norm(), 1e-12) << model.joints[k].name;
      ++k;
    }
    const double V = potentialEnergy(model, dm, q, model.inertial);
    EXPECT_NEAR(potentialEnergy(e, de, th, e.inertial), V, 1e-12 * std::abs(V));
  }
}
