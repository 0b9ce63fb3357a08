#include "mindyn/ik.hpp"

#include <time.h>

#include <cmath>
#include <limits>

#include "mindyn/dynamics.hpp"
#include "mindyn/spatial.hpp"

namespace mindyn {

namespace {

// CPU time of the calling thread [s].
double threadSeconds() noexcept {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}
}  // namespace

// ---------------------------------------------------------------------------------------------
ChainKinematics::ChainKinematics(const Model& model) : model_(model), data_(model_) {}

void ChainKinematics::pose(const Eigen::Ref<const Eigen::VectorXd>& q,
                           Eigen::Isometry3d& T) noexcept {
  forwardKinematics(model_, data_, q);
  const int last = model_.nq() - 1;
  T.linear() = data_.R0[last] * model_.tool.linear();
  T.translation() = data_.p0[last] + data_.R0[last] * model_.tool.translation();
}

void ChainKinematics::poseAndJacobian(const Eigen::Ref<const Eigen::VectorXd>& q,
                                      Eigen::Isometry3d& T, Eigen::Ref<Matrix6Xd> J) noexcept {
  pose(q, T);
  // Column k: the joint's unit twist S_k (link k, about its origin) in the base frame, its
  // linear part moved to the tool origin.
  // Joints that do not support the last link (other branches of a tree) have zero columns.
  const Eigen::Vector3d pt = T.translation();
  if (!model_.parents.empty()) J.setZero();
  for (int k = model_.nq() - 1; k >= 0; k = model_.parent(k)) {
    const Eigen::Vector3d w = data_.R0[k] * data_.S[k].head<3>();
    J.col(k).head<3>() = data_.R0[k] * data_.S[k].tail<3>() + w.cross(pt - data_.p0[k]);
    J.col(k).tail<3>() = w;
  }
}

// ---------------------------------------------------------------------------------------------
const char* toString(IkStatus status) {
  switch (status) {
    case IkStatus::Converged:
      return "converged";
    case IkStatus::NotConverged:
      return "not converged";
    case IkStatus::Timeout:
      return "timeout";
    case IkStatus::InvalidTarget:
      return "invalid target";
  }
  return "unknown";
}

IkSolver::IkSolver(const Model& model, IkOptions options)
    : n_(model.nq()),
      options_(options),
      kin_(model),
      lower_(model.nq()),
      upper_(model.nq()),
      wraps_(model.nq()),
      revolute_(model.nq()),
      rng_(options.seed),
      x_(model.nq()),
      xc_(model.nq()),
      dq_(model.nq()),
      best_(model.nq()),
      xt_(model.nq()),
      fixed_(model.nq()),
      J_(6, model.nq()),
      Jc_(6, model.nq()),
      Jw_(6, model.nq()) {
  for (int k = 0; k < n_; ++k) {
    const Joint& j = model.joints[k];
    const bool rev = j.type == JointType::Revolute;
    revolute_[k] = rev;
    double lo = j.limits.lower, hi = j.limits.upper;
    if (!std::isfinite(lo) || !std::isfinite(hi) || !(hi >= lo)) {
      lo = rev ? -kPi : -options.unlimited_prismatic_range;
      hi = rev ? kPi : options.unlimited_prismatic_range;
    }
    lower_[k] = lo;
    upper_[k] = hi;
    wraps_[k] = rev;
  }
}

void IkSolver::bringInside(Eigen::Ref<Eigen::VectorXd> q) const noexcept {
  for (int k = 0; k < n_; ++k) {
    double v = q[k];
    const double lo = lower_[k], hi = upper_[k];
    if (v >= lo && v <= hi) continue;
    if (wraps_[k] && std::isfinite(v)) {
      // the representative of v in [lo, lo + 2 pi)
      double w = lo + std::fmod(v - lo, kTwoPi);
      if (w < lo) w += kTwoPi;
      if (w <= hi) {
        q[k] = w;
        continue;
      }
      // outside: go to the nearer limit along the circle
      const double to_hi = w - hi, to_lo = lo + kTwoPi - w;
      q[k] = to_hi <= to_lo ? hi : lo;
      continue;
    }
    q[k] = v < lo ? lo : (v > hi ? hi : (lo + hi) / 2);
  }
}

void IkSolver::randomPoint(Eigen::Ref<Eigen::VectorXd> q) noexcept {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < n_; ++k) q[k] = lower_[k] + (upper_[k] - lower_[k]) * u(rng_);
}

IkResult IkSolver::solve(const Eigen::Isometry3d& target,
                         const Eigen::Ref<const Eigen::VectorXd>& q0,
                         Eigen::Ref<Eigen::VectorXd> q) noexcept {
  const double start = options_.max_time > 0 ? threadSeconds() : 0.0;
  IkResult result;
  const Eigen::Matrix3d Rt = target.linear();
  if (!target.matrix().allFinite() ||
      (Rt.transpose() * Rt - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-6 ||
      Rt.determinant() < 0) {
    result.status = IkStatus::InvalidTarget;
    q = q0;
    return result;
  }
  rng_.seed(options_.seed);
  const double tol = options_.tolerance;
  const double wr = options_.orientation_weight;
  // the error the tolerance applies to: the pose's, or with no weight on the orientation the
  // position's alone (the rotation is then free)
  const auto errorOf = [&target, wr](const Eigen::Isometry3d& X) noexcept {
    return wr > 0 ? logError(X, target) : (target.translation() - X.translation()).norm();
  };
  Eigen::Matrix<double, 6, 1> W;
  W << 1, 1, 1, wr, wr, wr;
  Eigen::Isometry3d T, Tc;
  Eigen::Matrix<double, 6, 1> e, ec;
  Eigen::Matrix<double, 6, 6> A;
  double best_err = std::numeric_limits<double>::infinity();
  best_ = q0;

  for (int attempt = 0; attempt < options_.max_attempts; ++attempt) {
    result.attempts = attempt + 1;
    if (attempt == 0) {
      x_ = q0;
      for (int k = 0; k < n_; ++k)
        if (!std::isfinite(x_[k])) x_[k] = 0.5 * (lower_[k] + upper_[k]);
    } else {
      randomPoint(x_);
    }
    bringInside(x_);
    kin_.poseAndJacobian(x_, T, J_);
    poseError(T, target, e);
    double err = errorOf(T);
    double cost = 0.5 * (W.asDiagonal() * e).squaredNorm();
    double mu = 0.3;
    double err_checkpoint = err;
    for (int it = 0; it < options_.max_iterations; ++it) {
      if (err < best_err) {
        best_err = err;
        best_ = x_;
      }
      if (err <= tol) {
        // Converged: Newton steps (damping at rounding level) from here, the best point kept.
        // Near a singularity the first steps may overshoot before they converge, so a step is
        // taken even when it does not improve, up to kIkRefineSteps or a thousandfold growth.
        // Below `noise` (a few hundred roundings of the target's size) nothing is to gain.
        const double noise =
            256 * std::numeric_limits<double>::epsilon() * (1.0 + target.translation().norm());
        double best = err;
        best_ = x_;
        for (int r = 0; r < kIkRefineSteps && err > noise; ++r) {
          ++result.iterations;
          std::fill(fixed_.begin(), fixed_.end(), 0);
          // A joint the step takes past a limit is held there and the step taken again
          // without it (at most one pass per joint).
          for (int pass = 0; pass <= n_; ++pass) {
            Jw_.noalias() = W.asDiagonal() * J_;
            for (int k = 0; k < n_; ++k)
              if (fixed_[k]) Jw_.col(k).setZero();
            A.noalias() = Jw_ * Jw_.transpose();
            A.diagonal().array() += 1e-12 * (1.0 + A.diagonal().maxCoeff());
            llt_.compute(A);
            const Eigen::Matrix<double, 6, 1> y = llt_.solve(W.asDiagonal() * e);
            dq_.noalias() = Jw_.transpose() * y;
            xc_ = x_ + dq_;
            xt_ = xc_;
            bringInside(xc_);
            bool held = false;
            for (int k = 0; k < n_; ++k)
              if (std::abs(std::remainder(xc_[k] - xt_[k], kTwoPi)) > 1e-12 && !fixed_[k]) {
                fixed_[k] = 1;
                held = true;
              }
            if (!held) break;
          }
          kin_.poseAndJacobian(xc_, Tc, Jc_);
          const double errc = errorOf(Tc);
          if (!(errc <= 1e3 * best)) break;
          poseError(Tc, target, e);
          x_.swap(xc_);
          J_.swap(Jc_);
          err = errc;
          if (err < best) {
            best = err;
            best_ = x_;
          } else if (r > 0 && err >= 0.5 * best && best <= 1e3 * noise) {
            break;  // at rounding level: no further gain
          }
        }
        q = best_;
        result.status = IkStatus::Converged;
        result.error = best;
        return result;
      }
      ++result.iterations;
      if (options_.max_time > 0 && threadSeconds() - start > options_.max_time) {
        q = best_;
        result.status = IkStatus::Timeout;
        result.error = best_err;
        return result;
      }
      // damped least squares step on the weighted error: dq = Jw^T (Jw Jw^T + lambda I)^-1 ew
      Jw_.noalias() = W.asDiagonal() * J_;
      A.noalias() = Jw_ * Jw_.transpose();
      const double lambda = mu * cost + 1e-12;
      A.diagonal().array() += lambda;
      llt_.compute(A);
      const Eigen::Matrix<double, 6, 1> y = llt_.solve(W.asDiagonal() * e);
      dq_.noalias() = Jw_.transpose() * y;
      xc_ = x_ + dq_;
      bringInside(xc_);
      kin_.poseAndJacobian(xc_, Tc, Jc_);
      poseError(Tc, target, ec);
      const double errc = errorOf(Tc);
      const double costc = 0.5 * (W.asDiagonal() * ec).squaredNorm();
      if (costc < cost) {
        x_.swap(xc_);
        J_.swap(Jc_);
        e = ec;
        err = errc;
        cost = costc;
        mu = std::max(mu * 0.5, 1e-3);
      } else {
        mu *= 10.0;
        if (mu > 1e8) break;  // no descent left: a local minimum or a limit; restart
      }
      // stagnation: restart when five iterations did not halve the error
      if ((it + 1) % 5 == 0) {
        if (err > 0.5 * err_checkpoint) break;
        err_checkpoint = err;
      }
    }
    if (err < best_err) {
      best_err = err;
      best_ = x_;
    }
  }
  q = best_;
  result.status = IkStatus::NotConverged;
  result.error = best_err;
  return result;
}

}  // namespace mindyn
