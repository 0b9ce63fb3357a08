// Forward kinematics and Jacobians through Orocos KDL, plus the Model -> KDL::Chain adapter.
//
// Conventions:
//  - the chain has one KDL::Segment per joint, named after the link it moves (its tip frame) and
//    holding a KDL::Joint named after the joint; a fixed segment "tool" is appended when
//    Model::tool is not the identity;
//  - segment inertias are the model's classical parameters (about the link origin, link axes);
//  - Jacobians follow KDL: rows 0-2 linear velocity, rows 3-5 angular velocity, reference point
//    the tool frame origin, all expressed in the base frame.
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#include <kdl/frames.hpp>
#include <kdl/jacobian.hpp>
#include <kdl/jntarray.hpp>
#include <memory>

#include "mindyn/model.hpp"

namespace mindyn {

/// One KDL segment per joint, with its inertia unless `with_inertia` is false, then the tool
/// segment. Throws ModelError for a link with zero mass but nonzero first moments.
KDL::Chain toKdlChain(const Model& model, bool with_inertia = true);

/// Eigen <-> KDL frame conversions.
Eigen::Isometry3d toEigen(const KDL::Frame& frame);
KDL::Frame toKdl(const Eigen::Isometry3d& T);

/// Pose and Jacobian of a model's chain with KDL solvers; buffers are allocated once at
/// construction. Not thread-safe: use one object per thread.
class Kinematics {
 public:
  explicit Kinematics(const Model& model);
  Kinematics(const Kinematics& other);
  Kinematics& operator=(const Kinematics& other);
  Kinematics(Kinematics&&) = default;
  Kinematics& operator=(Kinematics&&) = default;
  ~Kinematics();

  int nq() const { return n_; }
  const KDL::Chain& chain() const { return *chain_; }

  /// Pose in the base frame of link `link` (0..n-1: the link moved by joint `link`), or of the
  /// tool frame for -1. Throws std::invalid_argument for a wrong-sized q, std::out_of_range for
  /// a bad link index.
  Eigen::Isometry3d pose(const Eigen::VectorXd& q, int link = -1);

  /// 6 x n geometric Jacobian of the tool frame (KDL convention, see above).
  Eigen::Matrix<double, 6, Eigen::Dynamic> jacobian(const Eigen::VectorXd& q);
  /// The same into a preallocated 6 x n matrix, allocating nothing.
  void jacobian(const Eigen::VectorXd& q, Eigen::Ref<Eigen::Matrix<double, 6, Eigen::Dynamic>> J);

 private:
  void setup();
  void setQ(const Eigen::VectorXd& q);

  int n_ = 0;
  std::unique_ptr<KDL::Chain> chain_;  // on the heap: the solvers keep a reference to it
  std::unique_ptr<KDL::ChainFkSolverPos_recursive> fk_;
  std::unique_ptr<KDL::ChainJntToJacSolver> jac_solver_;
  KDL::JntArray q_;
  KDL::Jacobian jac_;
  KDL::Frame frame_;
};

}  // namespace mindyn
