// Position inverse kinematics by damped least squares (Levenberg-Marquardt) on the tool pose,
// inside the joint limits, with seeded random restarts; and the tool pose and geometric Jacobian
// it runs on, from the kinematic pass of the dynamics (forwardKinematics, dynamics.hpp; no KDL).
//
// Steps: damped least squares on the twist that moves the current tool frame onto the target in
// the base frame, e = poseError(T, target) (spatial.hpp). Convergence test: logError(T, target),
// the norm of the SE(3) logarithm of T_target^-1 T (with orientation_weight 0, of the position
// error alone), within the tolerance, the joints inside their limits. A converged point is then
// refined by Newton steps (joints a step would take past a limit held there), at most
// kIkRefineSteps, until the norm is at rounding level; the best point is returned. The answer is as
// precise as the arithmetic allows (about 1e-15 m or rad) unless a limit prevents it.
//
// After construction nothing allocates or throws: IkSolver::solve() and ChainKinematics::pose()
// and poseAndJacobian() are real-time safe. An object holds its workspace: one per thread.
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <random>
#include <vector>

#include "mindyn/data.hpp"
#include "mindyn/model.hpp"

namespace mindyn {

using Matrix6Xd = Eigen::Matrix<double, 6, Eigen::Dynamic>;

/// Tool pose and geometric Jacobian of a model's chain (rows vx vy vz wx wy wz in the base frame,
/// reference point the tool origin: the KDL convention of kinematics.hpp). The tool is fixed to
/// the last link (n); on a tree, the columns of joints off its root path are zero.
class ChainKinematics {
 public:
  explicit ChainKinematics(const Model& model);
  int nq() const { return model_.nq(); }
  /// Tool pose at q.
  void pose(const Eigen::Ref<const Eigen::VectorXd>& q, Eigen::Isometry3d& T) noexcept;
  /// Tool pose and Jacobian at q.
  void poseAndJacobian(const Eigen::Ref<const Eigen::VectorXd>& q, Eigen::Isometry3d& T,
                       Eigen::Ref<Matrix6Xd> J) noexcept;

 private:
  Model model_;
  Data data_;
};

/// Most Newton steps taken after convergence to refine the answer.
inline constexpr int kIkRefineSteps = 10;

enum class IkStatus {
  Converged,      // pose error within tolerance, joints inside the limits
  NotConverged,   // every attempt used up its iterations (target unreachable or too hard)
  Timeout,        // the time budget ran out first
  InvalidTarget,  // the target pose is not finite or not a rotation
};

const char* toString(IkStatus status);

struct IkOptions {
  double tolerance = 1e-5;   // of the norm of the pose error's SE(3) logarithm [m, rad]
  int max_iterations = 100;  // per attempt
  int max_attempts = 100;    // the first from q0, the others from random points inside limits
  // CPU seconds of the calling thread for one solve (0: no limit). In a real-time thread this is
  // wall time; on a loaded machine preemption does not count against the budget.
  double max_time = 0.005;
  // [m/rad]: weight of rotation errors against positions; 0: the position alone (the rotation
  // free, the tolerance and IkResult::error then the position error's norm [m])
  double orientation_weight = 0.3;
  unsigned seed = 42;  // of the restart points (reset at every solve: reproducible)
  // Range used for joints without limits: revolute [-pi, pi], prismatic [-range, range].
  double unlimited_prismatic_range = 1.0;
};

struct IkResult {
  IkStatus status = IkStatus::NotConverged;
  double error = 0;    // norm of the SE(3) logarithm of T_target^-1 T at the answer (position
                       // only: of the position error)
  int iterations = 0;  // over all attempts
  int attempts = 0;
  bool success() const { return status == IkStatus::Converged; }
};

class IkSolver {
 public:
  explicit IkSolver(const Model& model, IkOptions options = {});

  int nq() const { return n_; }
  const IkOptions& options() const { return options_; }
  void setOptions(const IkOptions& options) { options_ = options; }
  /// The limits used: the model's, or the unlimited ranges above (revolute: [-pi, pi], with
  /// `wraps` true meaning the joint may turn freely).
  const Eigen::VectorXd& lower() const { return lower_; }
  const Eigen::VectorXd& upper() const { return upper_; }

  /// Solves for q (size n) with tool pose `target`, starting from q0 (size n; values outside the
  /// limits are brought inside). On failure q holds the best point found.
  IkResult solve(const Eigen::Isometry3d& target, const Eigen::Ref<const Eigen::VectorXd>& q0,
                 Eigen::Ref<Eigen::VectorXd> q) noexcept;

  ChainKinematics& kinematics() { return kin_; }

 private:
  void bringInside(Eigen::Ref<Eigen::VectorXd> q) const noexcept;
  void randomPoint(Eigen::Ref<Eigen::VectorXd> q) noexcept;

  int n_;
  IkOptions options_;
  ChainKinematics kin_;
  Eigen::VectorXd lower_, upper_;
  std::vector<bool> wraps_;  // revolute with a range of at least 2 pi: angles may be shifted
  std::vector<bool> revolute_;
  std::mt19937 rng_;
  // work
  Eigen::VectorXd x_, xc_, dq_, best_, xt_;
  std::vector<char> fixed_;  // refinement: joints held at a limit
  Matrix6Xd J_, Jc_, Jw_;
  Eigen::LLT<Eigen::Matrix<double, 6, 6>> llt_;
};

}  // namespace mindyn
