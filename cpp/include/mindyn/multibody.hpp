// Rigid-body dynamics and kinematics of a model with joints of any kind (model.hpp, JointType):
// revolute, prismatic, spherical, universal, cylindrical, planar and free-flyer joints, a serial
// chain or a tree, with a fixed base or a floating one (a free-flyer or planar joint at the root).
//
// q has model.configSize() entries and v, a, tau model.velocitySize() (Pinocchio's nq and nv, its
// joint conventions: see JointType). tau of a free-flyer joint is the wrench (force; torque) the
// joint transmits to its child body, in that body's axes about its origin, force first as its
// velocity; of a planar joint (fx, fy, tz), of a spherical joint the torque, in the same way.
// `params` holds the ten classical parameters of each link (model.hpp, XX .. M about the link
// origin), 10 n entries: rotor inertia and friction have no place on a multi-DOF joint.
//
// Spatial vectors inside are (angular; linear) as in dynamics.hpp. Every function here allocates
// nothing and throws nothing after MultibodyData is built; sizes are preconditions, checked once
// at setup with checkMultibodySizes (and the unit norms of q with checkConfiguration).
// On a model whose joints are all revolute or prismatic these functions give what dynamics.hpp
// gives with the inertial-only layout.
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <random>
#include <vector>

#include "mindyn/dynamics.hpp"
#include "mindyn/model.hpp"

namespace mindyn {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// Workspace of the multibody algorithms, built once per model; one thread at a time.
struct MultibodyData {
  explicit MultibodyData(const Model& model);

  int n, nq, nv;
  std::vector<int> iq, iv, dof;  // per joint: first q entry, first v entry, nv of the joint
  // Per joint, in link-k coordinates: the motion subspace (first dof[k] columns) and the bias
  // acceleration dS/dt v of the joint.
  std::vector<Matrix6d> S;
  std::vector<Vector6d> c;
  std::vector<Eigen::Matrix3d> R, R0;  // link k in its parent link, and in the base frame
  std::vector<Eigen::Vector3d> p, p0;
  std::vector<Vector6d> v, a, f;
  std::vector<Vector6d> vr, ar;  // Slotine-Li: reference velocity and acceleration of each link
  Eigen::Matrix<double, 6, 10> F;
  Eigen::VectorXd zeros, unit, tmp;  // nv
  Eigen::MatrixXd M;                 // nv x nv
  Eigen::MatrixXd Yw;                // nv x 10 n, the Coriolis matrix's regressor
  Eigen::LLT<Eigen::MatrixXd> llt;
};

/// Poses of every link (data.R, p, R0, p0) and the joints' motion subspaces at q.
void forwardKinematics(const Model& model, MultibodyData& data, const VecRef& q) noexcept;

/// The axes of a frame Jacobian's rows (Pinocchio's ReferenceFrame): the base frame's
/// (LOCAL_WORLD_ALIGNED) or the frame's own (LOCAL).
enum class ReferenceFrame { LocalWorldAligned, Local };

/// The Jacobian J (6 x nv) of a frame fixed to link `link` (0-based: the link joint `link`
/// moves) at `placement` in that link's frame, at q: (v; w) = J v_q with v the velocity of the
/// frame's origin and w the frame's angular velocity, in the base axes (LocalWorldAligned) or in
/// the frame's own axes (Local) -- LINEAR FIRST, as Pinocchio's getFrameJacobian. Column block
/// of joint k: its motion subspace S_k (link k, about its origin) carried to the frame's origin;
/// zero for the joints not on the path from the base to `link`. Runs forwardKinematics (data.R0,
/// p0 are the poses at q afterwards); 0 <= link < n is a precondition.
void frameJacobian(const Model& model, MultibodyData& data, const VecRef& q, int link,
                   const Eigen::Isometry3d& placement, ReferenceFrame frame, MatOut J) noexcept;

/// Recursive Newton-Euler inverse dynamics: tau = M(q) a + b(q, v) + g(q) (Pinocchio's rnea).
void inverseDynamics(const Model& model, MultibodyData& data, const VecRef& q, const VecRef& v,
                     const VecRef& a, const VecRef& params, VecOut tau) noexcept;

/// The joint-torque regressor W (nv x 10 n), tau = W params, with Pinocchio's
/// computeJointTorqueRegressor's rows and mindyn's parameter order (toPinocchioOrder maps it).
void regressor(const Model& model, MultibodyData& data, const VecRef& q, const VecRef& v,
               const VecRef& a, MatOut W) noexcept;

/// The joint-space inertia matrix M(q) (nv x nv, both triangles).
void massMatrix(const Model& model, MultibodyData& data, const VecRef& q, const VecRef& params,
                MatOut M) noexcept;

/// a = M(q)^-1 (tau - b(q, v) - g(q)); false, leaving a unchanged, when M(q) is not positive
/// definite for these parameters.
bool forwardDynamics(const Model& model, MultibodyData& data, const VecRef& q, const VecRef& v,
                     const VecRef& tau, const VecRef& params, VecOut a) noexcept;

/// The momentum of the whole system (linear; angular about the base origin), both in base axes:
/// the sum of the links' I v carried to the base (note: linear first, as Pinocchio's Force).
Vector6d momentum(const Model& model, MultibodyData& data, const VecRef& q, const VecRef& v,
                  const VecRef& params) noexcept;

/// Kinetic and potential energy (the potential zero at the base origin, gravity model.gravity).
double kineticEnergy(const Model& model, MultibodyData& data, const VecRef& q, const VecRef& v,
                     const VecRef& params) noexcept;
double potentialEnergy(const Model& model, MultibodyData& data, const VecRef& q,
                       const VecRef& params) noexcept;

/// The Slotine-Li regressor Y (nv x 10 n): Y(q, v, vr, ar) params = M(q) ar + C(q, v) vr + g(q)
/// (slotine_li.hpp: the Newton-Euler factorisation f = I (a_r - v x v_r / 2) + (v x* I v_r +
/// v_r x* I v) / 2, with dM/dt - 2 C skew-symmetric), vr and ar of velocitySize entries.
void slotineLiRegressor(const Model& model, MultibodyData& data, const VecRef& q, const VecRef& v,
                        const VecRef& vr, const VecRef& ar, MatOut Y) noexcept;

/// The Coriolis matrix C(q, v) (nv x nv) of the same factorisation for these parameters:
/// C(q, v) v = b(q, v), dM/dt - 2 C skew-symmetric.
void coriolisMatrix(const Model& model, MultibodyData& data, const VecRef& q, const VecRef& v,
                    const VecRef& params, MatOut C) noexcept;

/// Kinetic and potential energy regressors (rows of 10 n): K = wK params, P = wP params.
void energyRegressors(const Model& model, MultibodyData& data, const VecRef& q, const VecRef& v,
                      VecOut wK, VecOut wP) noexcept;

/// A random configuration of the model into q (configSize entries): revolute and prismatic
/// joints uniform within their limits (+-pi or +-1 where none), unit quaternions uniform on the
/// sphere, the other coordinates uniform in [-1, 1] (angles in [-pi, pi]).
void randomConfiguration(const Model& model, std::mt19937& rng, Eigen::VectorXd& q);

/// Throws std::invalid_argument naming the argument whose size does not fit the model (q:
/// configSize, v and a: velocitySize, params: 10 n; a negative size is not checked).
void checkMultibodySizes(const Model& model, long q, long v, long a, long params);

}  // namespace mindyn
