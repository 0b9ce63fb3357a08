#include "mindyn/momentum_observer.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "mindyn/momentum.hpp"

namespace mindyn {

namespace {

void requireFinite(const Eigen::VectorXd& v, long size, const char* what) {
  if (v.size() != size)
    throw ModelError(std::string(what) + " has " + std::to_string(v.size()) +
                     " entries; expected " + std::to_string(size));
  if (!v.allFinite()) throw ModelError(std::string(what) + " must be finite");
}

}  // namespace

double MomentumObserver::defaultGain(double period) { return 1.0 / (10.0 * period); }

MomentumObserver::MomentumObserver(const Model& model, const BaseParameters& base,
                                   const Eigen::VectorXd& values, const Eigen::VectorXd& gains,
                                   double period, const Eigen::VectorXd& offset, bool held_torque)
    : model_(model),
      base_(base),
      n_(model.nq()),
      period_(period),
      held_(held_torque),
      values_(values),
      k_(gains),
      offset_(offset.size() ? offset : Eigen::VectorXd::Zero(model.nq())),
      data_(model) {
  const int n = n_, P = base.layout.size(n), nb = base.eom.size();
  if (!(std::isfinite(period) && period > 0))
    throw ModelError("the observer period must be a positive number of seconds");
  requireFinite(values_, nb, "the base-parameter values");
  requireFinite(k_, n, "the observer gains");
  requireFinite(offset_, n, "the torque offsets");
  for (int j = 0; j < n; ++j)
    if (!(k_[j] > 0 && k_[j] * period < 2.0))
      throw ModelError("observer gain K_O of joint " + std::to_string(j + 1) + " is " +
                       std::to_string(k_[j]) +
                       " 1/s; expected 0 < K_O < 2 / period = " + std::to_string(2.0 / period) +
                       " (K_O T >= 2 makes the discrete residual alternate)");
  c_ = k_.array() / (1.0 + 0.5 * period * k_.array());
  if (base.layout.friction) {
    const int per = base.layout.perLink(), first = 10 + (base.layout.rotor ? 1 : 0);
    const auto& piv = base.eom.decision.pivots;
    for (size_t b = 0; b < piv.size(); ++b)
      if (piv[b] < base.layout.linkSize(n) && piv[b] % per >= first)
        friction_.push_back(static_cast<long>(b));
  }
  W_.setZero(n, P);
  Wp_.setZero(n, P);
  Wl_.setZero(n, P);
  Wpb_.setZero(n, nb);
  Wlb_.setZero(n, nb);
  for (Eigen::VectorXd* v : {&p_, &beta_, &p0_, &s_, &r_, &tau_prev_, &beta_prev_}) v->setZero(n);
}

void MomentumObserver::evaluate(const VecRef& q, const VecRef& dq) noexcept {
  baseMomentumRegressors(model_, data_, base_, q, dq, Wp_, Wl_, Wpb_, Wlb_);
  if (!friction_.empty()) {  // friction columns of the equations of motion (zero in W_l)
    regressor(model_, data_, q, dq, data_.zeros, base_.layout, W_);
    const auto& piv = base_.eom.decision.pivots;
    for (long b : friction_) Wlb_.col(b) += W_.col(piv[static_cast<size_t>(b)]);
  }
  p_.noalias() = Wpb_ * values_;
  beta_.noalias() = Wlb_ * values_;
  beta_ += offset_;
}

void MomentumObserver::reset(const VecRef& q, const VecRef& dq, const VecRef& tau) noexcept {
  evaluate(q, dq);
  p0_ = p_;
  s_.setZero();
  r_.setZero();
  tau_prev_ = tau;
  beta_prev_ = beta_;
}

void MomentumObserver::step(const VecRef& q, const VecRef& dq, const VecRef& tau,
                            VecOut r) noexcept {
  step(q, dq, tau, period_, r);
}

void MomentumObserver::step(const VecRef& q, const VecRef& dq, const VecRef& tau, double dt,
                            VecOut r) noexcept {
  evaluate(q, dq);
  const double T = dt, h = 0.5 * dt;
  const bool own = dt == period_;
  for (int j = 0; j < n_; ++j) {
    const double torque = held_ ? T * tau_prev_[j] : h * (tau[j] + tau_prev_[j]);
    const double s = s_[j] + torque - h * (beta_[j] + beta_prev_[j]) + h * r_[j];
    const double c = own ? c_[j] : k_[j] / (1.0 + h * k_[j]);
    const double rj = c * (p_[j] - p0_[j] - s);
    s_[j] = s + h * rj;  // the integral with r_k's own half-step
    r_[j] = rj;
  }
  tau_prev_ = tau;
  beta_prev_ = beta_;
  r = r_;
}

}  // namespace mindyn
