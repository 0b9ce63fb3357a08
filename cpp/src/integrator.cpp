#include "mindyn/integrator.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "drive_terms.hpp"

namespace mindyn {

Integrator::Integrator(const Model& model, const Eigen::VectorXd& params, ParameterLayout layout,
                       double coulomb_smoothing)
    : model_(model),
      n_(model.nq()),
      layout_(layout),
      params_(params),
      friction_(Eigen::MatrixXd::Zero(model.nq(), 3)),
      eps_(coulomb_smoothing) {
  checkSizes(model, layout, -1, -1, -1, params.size());
  if (!params.allFinite()) throw std::invalid_argument("params contains NaN or infinite values");
  if (!(eps_ >= 0) || !std::isfinite(eps_))
    throw std::invalid_argument("coulomb_smoothing must be a finite number >= 0, got " +
                                std::to_string(eps_));
  if (layout.friction) {  // all but the viscous column, applied as torques
    for (int k = 0; k < n_; ++k)
      for (int i = 1; i < layout.friction_columns; ++i) {
        friction_(k, i) = params_[layout.frictionIndex(k, i)];
        params_[layout.frictionIndex(k, i)] = 0.0;
      }
  }
  for (Eigen::VectorXd* v : {&tau_, &k1_, &k2_, &k3_, &k4_, &qs_, &vs_, &v2_, &v3_}) v->resize(n_);
}

bool Integrator::acceleration(Data& data, const VecRef& q, const VecRef& dq, const VecRef& tau,
                              VecOut ddq) noexcept {
  // The friction torques other than the viscous one of each slot at its velocity (a motor's on
  // the motor side), through the transmission to the joints.
  tau_ = tau;
  if (!layout_.friction) return forwardDynamics(model_, data, q, dq, tau_, params_, layout_, ddq);
  const bool motors = model_.motorSide();
  for (int k = 0; k < n_; ++k) {
    const double v = drive::motorVelocity(model_, k, dq);
    double phi[3] = {0.0, 0.0, 0.0};
    slotFrictionShapes(model_, k, v, phi, eps_);
    double f = 0.0;
    for (int i = 1; i < layout_.friction_columns; ++i) f += friction_(k, i) * phi[i];
    if (f == 0.0) continue;
    if (motors)
      tau_ -= f * model_.transmission.T.row(k).transpose();
    else
      tau_[k] -= f;
  }
  return forwardDynamics(model_, data, q, dq, tau_, params_, layout_, ddq);
}

bool Integrator::step(Data& data, VecOut q, VecOut dq, const VecRef& tau, double dt,
                      int substeps) noexcept {
  if (!(dt > 0) || substeps < 1) return false;
  const double h = dt / substeps;
  for (int i = 0; i < substeps; ++i) {
    if (!acceleration(data, q, dq, tau, k1_)) return false;
    qs_ = q + 0.5 * h * dq;
    v2_ = dq + 0.5 * h * k1_;
    if (!acceleration(data, qs_, v2_, tau, k2_)) return false;
    qs_ = q + 0.5 * h * v2_;
    v3_ = dq + 0.5 * h * k2_;
    if (!acceleration(data, qs_, v3_, tau, k3_)) return false;
    qs_ = q + h * v3_;
    vs_ = dq + h * k3_;
    if (!acceleration(data, qs_, vs_, tau, k4_)) return false;
    q += h / 6.0 * (dq + 2.0 * v2_ + 2.0 * v3_ + vs_);
    dq += h / 6.0 * (k1_ + 2.0 * k2_ + 2.0 * k3_ + k4_);
    if (!q.allFinite() || !dq.allFinite()) return false;
  }
  return true;
}

}  // namespace mindyn
