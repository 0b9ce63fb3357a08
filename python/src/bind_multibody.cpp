// Python bindings of the multibody dynamics (multibody.hpp): models with joints of several
// degrees of freedom and floating bases, q of configSize() and v of velocitySize() entries. One
// sample per call; errors are ModelError (mindyn.Error) in one line.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <optional>
#include <stdexcept>

#include "mindyn/multibody.hpp"
#include "py_types.hpp"

namespace py = pybind11;
using namespace mindyn;

namespace {

using Vec = Eigen::VectorXd;

// Checks sizes, finiteness and the unit norms of q; the parameters default to the model's.
Vec checked(const PyModel& s, const Vec& q, const Vec* v, const Vec* a, const char* a_name,
            const std::optional<Vec>& params) {
  const Model& m = s.model;
  const Vec p = params ? *params : m.inertial;
  try {
    checkMultibodySizes(m, q.size(), v ? v->size() : -1, -1, p.size());
    if (a && a->size() != m.velocitySize())
      throw std::invalid_argument(std::string(a_name) + " has " + std::to_string(a->size()) +
                                  " entries; the model's velocity has " +
                                  std::to_string(m.velocitySize()));
    const std::pair<const Vec*, const char*> all[] = {
        {&q, "q"}, {v, "v"}, {a, a_name}, {&p, "params"}};
    for (const auto& [x, name] : all)
      if (x && !x->allFinite())
        throw std::invalid_argument(std::string(name) + " has a value that is not finite");
    checkConfiguration(m, q);
  } catch (const std::invalid_argument& e) {
    throw ModelError(e.what());
  }
  return p;
}

}  // namespace

void bindMultibody(py::module_& m) {
  m.def(
      "multibody_inverse_dynamics",
      [](const PyModel& s, const Vec& q, const Vec& v, const Vec& a,
         const std::optional<Vec>& params) {
        const Vec p = checked(s, q, &v, &a, "a", params);
        MultibodyData data(s.model);
        Vec tau(data.nv);
        inverseDynamics(s.model, data, q, v, a, p, tau);
        return tau;
      },
      py::arg("model"), py::arg("q"), py::arg("v"), py::arg("a"), py::arg("params") = py::none());
  m.def(
      "multibody_regressor",
      [](const PyModel& s, const Vec& q, const Vec& v, const Vec& a) {
        checked(s, q, &v, &a, "a", std::nullopt);
        MultibodyData data(s.model);
        Eigen::MatrixXd W(data.nv, 10 * data.n);
        regressor(s.model, data, q, v, a, W);
        return W;
      },
      py::arg("model"), py::arg("q"), py::arg("v"), py::arg("a"));
  m.def(
      "multibody_mass_matrix",
      [](const PyModel& s, const Vec& q, const std::optional<Vec>& params) {
        const Vec p = checked(s, q, nullptr, nullptr, "", params);
        MultibodyData data(s.model);
        Eigen::MatrixXd M(data.nv, data.nv);
        massMatrix(s.model, data, q, p, M);
        return M;
      },
      py::arg("model"), py::arg("q"), py::arg("params") = py::none());
  m.def(
      "multibody_forward_dynamics",
      [](const PyModel& s, const Vec& q, const Vec& v, const Vec& tau,
         const std::optional<Vec>& params) {
        const Vec p = checked(s, q, &v, &tau, "tau", params);
        MultibodyData data(s.model);
        Vec a(data.nv);
        if (!forwardDynamics(s.model, data, q, v, tau, p, a))
          throw ModelError("the mass matrix is not positive definite for these parameters");
        return a;
      },
      py::arg("model"), py::arg("q"), py::arg("v"), py::arg("tau"), py::arg("params") = py::none());
  m.def(
      "multibody_slotine_li_regressor",
      [](const PyModel& s, const Vec& q, const Vec& v, const Vec& vr, const Vec& ar) {
        checked(s, q, &v, &vr, "vr", std::nullopt);
        checked(s, q, &v, &ar, "ar", std::nullopt);
        MultibodyData data(s.model);
        Eigen::MatrixXd Y(data.nv, 10 * data.n);
        slotineLiRegressor(s.model, data, q, v, vr, ar, Y);
        return Y;
      },
      py::arg("model"), py::arg("q"), py::arg("v"), py::arg("vr"), py::arg("ar"));
  m.def(
      "multibody_coriolis_matrix",
      [](const PyModel& s, const Vec& q, const Vec& v, const std::optional<Vec>& params) {
        const Vec p = checked(s, q, &v, nullptr, "", params);
        MultibodyData data(s.model);
        Eigen::MatrixXd C(data.nv, data.nv);
        coriolisMatrix(s.model, data, q, v, p, C);
        return C;
      },
      py::arg("model"), py::arg("q"), py::arg("v"), py::arg("params") = py::none());
  m.def(
      "multibody_momentum",
      [](const PyModel& s, const Vec& q, const Vec& v, const std::optional<Vec>& params) {
        const Vec p = checked(s, q, &v, nullptr, "", params);
        MultibodyData data(s.model);
        return Vec(momentum(s.model, data, q, v, p));
      },
      py::arg("model"), py::arg("q"), py::arg("v"), py::arg("params") = py::none(),
      "The system's momentum (linear; angular about the base origin), base axes.");
  m.def(
      "multibody_link_poses",
      [](const PyModel& s, const Vec& q) {
        checked(s, q, nullptr, nullptr, "", std::nullopt);
        MultibodyData data(s.model);
        forwardKinematics(s.model, data, q);
        std::vector<Eigen::Matrix4d> poses;
        for (int k = 0; k < data.n; ++k) {
          Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
          T.topLeftCorner<3, 3>() = data.R0[k];
          T.topRightCorner<3, 1>() = data.p0[k];
          poses.push_back(T);
        }
        return poses;
      },
      py::arg("model"), py::arg("q"), "The pose of every link in the base frame (n 4x4).");
  m.def(
      "multibody_frame_jacobian",
      [](const PyModel& s, const Vec& q, int link, const Eigen::Matrix4d& placement, bool local) {
        checked(s, q, nullptr, nullptr, "", std::nullopt);
        if (link < 0 || link >= s.model.nq())
          throw ModelError("link is " + std::to_string(link) + "; the model's links are 0.." +
                           std::to_string(s.model.nq() - 1));
        if (!placement.allFinite()) throw ModelError("placement has a value that is not finite");
        Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
        X.linear() = placement.topLeftCorner<3, 3>();
        X.translation() = placement.topRightCorner<3, 1>();
        MultibodyData data(s.model);
        Eigen::MatrixXd J(6, data.nv);
        frameJacobian(s.model, data, q, link, X,
                      local ? ReferenceFrame::Local : ReferenceFrame::LocalWorldAligned, J);
        return J;
      },
      py::arg("model"), py::arg("q"), py::arg("link"), py::arg("placement"), py::arg("local"),
      "The Jacobian (6 x nv, linear rows first) of the frame at `placement` (4x4) in link `link`: "
      "base axes, or the frame's own (local).");
  m.def(
      "multibody_energies",
      [](const PyModel& s, const Vec& q, const Vec& v, const std::optional<Vec>& params) {
        const Vec p = checked(s, q, &v, nullptr, "", params);
        MultibodyData data(s.model);
        return py::make_tuple(kineticEnergy(s.model, data, q, v, p),
                              potentialEnergy(s.model, data, q, p));
      },
      py::arg("model"), py::arg("q"), py::arg("v"), py::arg("params") = py::none());
}
