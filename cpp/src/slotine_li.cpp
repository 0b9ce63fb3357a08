#include "mindyn/slotine_li.hpp"

#include "body_terms.hpp"
#include "drive_terms.hpp"
#include "mindyn/spatial.hpp"

namespace mindyn {

namespace {

// Spatial inertia of ten classical parameters applied to a motion vector.
inline Vector6d applyInertia(const Eigen::Ref<const Eigen::VectorXd>& p, int c0,
                             const Vector6d& u) {
  const Eigen::Vector3d w = u.head<3>(), l = u.tail<3>();
  const Eigen::Vector3d h(p[c0 + 6], p[c0 + 7], p[c0 + 8]);
  Vector6d r;
  r[0] = p[c0 + 0] * w.x() + p[c0 + 1] * w.y() + p[c0 + 2] * w.z();
  r[1] = p[c0 + 1] * w.x() + p[c0 + 3] * w.y() + p[c0 + 4] * w.z();
  r[2] = p[c0 + 2] * w.x() + p[c0 + 4] * w.y() + p[c0 + 5] * w.z();
  r.head<3>() += h.cross(l);
  r.tail<3>() = p[c0 + 9] * l - h.cross(w);
  return r;
}

// Reference velocities and accelerations; needs data.R, data.p, data.v (actual velocities).
void referencePass(const Model& model, const Data& data, SlotineLiData& sl, const VecRef& dqr,
                   const VecRef& ddqr, bool with_gravity) noexcept {
  Vector6d a_base = Vector6d::Zero();
  if (with_gravity) a_base.tail<3>() = -model.gravity;
  for (int k = 0; k < sl.n; ++k) {
    const Vector6d& S = data.S[k];
    const Vector6d sj = S * dqr[k];
    const int pk = model.parent(k);
    const Vector6d& vp = pk < 0 ? Vector6d::Zero().eval() : sl.vr[pk];
    const Vector6d& ap = pk < 0 ? a_base : sl.ar[pk];
    sl.vr[k] = motionToChild(data.R[k], data.p[k], vp) + sj;
    sl.ar[k] = motionToChild(data.R[k], data.p[k], ap) + S * ddqr[k] + crossMotion(data.v[k], sj);
  }
}

}  // namespace

SlotineLiData::SlotineLiData(const Model& model, ParameterLayout l)
    : n(model.nq()),
      layout(l),
      vr(model.nq(), Vector6d::Zero()),
      ar(model.nq(), Vector6d::Zero()),
      F(Matrix6x10::Zero()),
      W(Eigen::MatrixXd::Zero(model.nq(), l.size(model.nq()))),
      zeros(Eigen::VectorXd::Zero(model.nq())),
      unit(Eigen::VectorXd::Zero(model.nq())) {}

void slotineLiRegressor(const Model& model, Data& data, SlotineLiData& sl, const VecRef& q,
                        const VecRef& dq, const VecRef& dqr, const VecRef& ddqr,
                        ParameterLayout layout, MatOut Y) noexcept {
  computeKinematics(model, data, q, dq, sl.zeros, false);
  referencePass(model, data, sl, dqr, ddqr, true);
  const int n = sl.n;
  Y.setZero();
  for (int j = 0; j < n; ++j) {
    const Vector6d& v = data.v[j];
    const Vector6d& vr = sl.vr[j];
    Matrix6x10& F = sl.F;
    F.noalias() = inertiaRegressor(sl.ar[j] - 0.5 * crossMotion(v, vr));
    F.noalias() += 0.5 * crossForceMatrix(v) * inertiaRegressor(vr);
    F.noalias() += 0.5 * crossForceMatrix(vr) * inertiaRegressor(v);
    const int c0 = j * layout.perLink();
    for (int k = j; k >= 0; k = model.parent(k)) {  // j and the joints that support it
      Y.block<1, 10>(k, c0).noalias() = data.S[k].transpose() * F;
      if (model.parent(k) >= 0) carryToParent(data.R[k], data.p[k], F, F);  // to the parent link
    }
  }
  drive::driveColumns(model, layout, dq, ddqr, Y);
  drive::offsetColumns(layout, Y);
}

void slotineLiBaseRegressor(const Model& model, Data& data, SlotineLiData& sl,
                            const BaseParameters& base, const VecRef& q, const VecRef& dq,
                            const VecRef& dqr, const VecRef& ddqr, MatOut Yb) noexcept {
  slotineLiRegressor(model, data, sl, q, dq, dqr, ddqr, base.layout, sl.W);
  const auto& piv = base.eom.decision.pivots;
  for (size_t b = 0; b < piv.size(); ++b) Yb.col(static_cast<long>(b)) = sl.W.col(piv[b]);
}

namespace {

// The force pass for a parameter vector; needs computeKinematics and referencePass.
// data.f collects the wrenches the children of each link carry into it.
void torquePass(const Model& model, Data& data, SlotineLiData& sl, const VecRef& dq,
                const VecRef& ddqr, const VecRef& params, ParameterLayout layout, bool joint_terms,
                VecOut tau) noexcept {
  const int n = sl.n;
  for (int k = 0; k < n; ++k) data.f[k].setZero();
  for (int k = n - 1; k >= 0; --k) {
    const int c0 = k * layout.perLink();
    const Vector6d& v = data.v[k];
    const Vector6d& vr = sl.vr[k];
    Vector6d f = applyInertia(params, c0, sl.ar[k] - 0.5 * crossMotion(v, vr));
    f += 0.5 * (crossForce(v, applyInertia(params, c0, vr)) +
                crossForce(vr, applyInertia(params, c0, v)));
    f += data.f[k];
    tau[k] = data.S[k].dot(f);
    const int pk = model.parent(k);
    if (pk >= 0) carryToParent<true>(data.R[k], data.p[k], f, data.f[pk]);
  }
  if (!joint_terms) return;
  drive::addDriveTorques(model, layout, params, dq, ddqr, tau);
  drive::addOffsets(layout, params, tau);
}

}  // namespace

void slotineLiTorque(const Model& model, Data& data, SlotineLiData& sl, const VecRef& q,
                     const VecRef& dq, const VecRef& dqr, const VecRef& ddqr, const VecRef& params,
                     ParameterLayout layout, VecOut tau, bool with_gravity,
                     bool joint_terms) noexcept {
  computeKinematics(model, data, q, dq, sl.zeros, false);
  referencePass(model, data, sl, dqr, ddqr, with_gravity);
  torquePass(model, data, sl, dq, ddqr, params, layout, joint_terms, tau);
}

void coriolisMatrix(const Model& model, Data& data, SlotineLiData& sl, const VecRef& q,
                    const VecRef& dq, const VecRef& params, ParameterLayout layout,
                    MatOut C) noexcept {
  computeKinematics(model, data, q, dq, sl.zeros, false);
  sl.unit.setZero();
  for (int j = 0; j < sl.n; ++j) {
    sl.unit[j] = 1.0;
    referencePass(model, data, sl, sl.unit, sl.zeros, false);
    torquePass(model, data, sl, dq, sl.zeros, params, layout, false, C.col(j));
    sl.unit[j] = 0.0;
  }
}

}  // namespace mindyn
