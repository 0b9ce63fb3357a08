#include "mindyn/momentum.hpp"

#include "drive_terms.hpp"
#include "mindyn/spatial.hpp"

namespace mindyn {

void momentumRegressors(const Model& model, Data& data, const VecRef& q, const VecRef& dq,
                        ParameterLayout layout, MatOut Wp, MatOut Wl) noexcept {
  // dP/dq: the gravity regressor (dq = ddq = 0; its rotor and friction columns are zero).
  regressor(model, data, q, data.zeros, data.zeros, layout, Wl);
  computeKinematics(model, data, q, dq, data.zeros, false);
  Wp.setZero();
  const int n = data.n;
  for (int j = 0; j < n; ++j) {
    // Momentum block of link j: h_j = F pi_j, about the link origin in link-j axes.
    const Eigen::Vector3d w = data.v[j].head<3>();
    const Eigen::Vector3d vo = data.v[j].tail<3>();
    Matrix6x10& F = data.F;
    F.setZero();
    F.block<3, 6>(0, 0) = inertiaMap(w);  // I w
    F.block<3, 3>(0, 6) = -skew(vo);      // m c x vo = -vo x (m c)
    F.block<3, 3>(3, 6) = skew(w);        // w x (m c)
    F.block<3, 1>(3, 9) = vo;             // m vo
    const int c0 = j * layout.perLink();
    for (int k = j; k >= 0; k = model.parent(k)) {  // j and the joints that support it
      Wp.block<1, 10>(k, c0).noalias() = data.S[k].transpose() * F;
      Wl.block<1, 10>(k, c0).noalias() -= crossMotion(data.v[k], data.S[k]).transpose() * F;
      if (model.parent(k) >= 0) carryToParent(data.R[k], data.p[k], F, F);
    }
  }
  drive::rotorColumns(model, layout, dq, Wp);  // Ia_k t_k v_k
}

void baseMomentumRegressors(const Model& model, Data& data, const BaseParameters& base,
                            const VecRef& q, const VecRef& dq, MatOut Wp, MatOut Wl, MatOut Wpb,
                            MatOut Wlb) noexcept {
  momentumRegressors(model, data, q, dq, base.layout, Wp, Wl);
  const auto& piv = base.eom.decision.pivots;
  for (size_t b = 0; b < piv.size(); ++b) {
    Wpb.col(static_cast<long>(b)) = Wp.col(piv[b]);
    Wlb.col(static_cast<long>(b)) = Wl.col(piv[b]);
  }
}

}  // namespace mindyn
