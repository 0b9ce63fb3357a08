// Python bindings of the control side: the Slotine-Li regressor and Coriolis matrix, the
// integrator of the closed-loop simulations (RK4 with the torque held), and the inverse-kinematics
// solver.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>

#include "mindyn/dynamics.hpp"
#include "mindyn/ik.hpp"
#include "mindyn/integrator.hpp"
#include "mindyn/slotine_li.hpp"
#include "py_args.hpp"
#include "py_types.hpp"

namespace py = pybind11;
using namespace mindyn;
using namespace mindyn::pyargs;

namespace {

// Calls f(q, dq, dqr, ddqr, data, out) per sample with a workspace of this call, out an
// r x c matrix stored row-major per sample.
template <class F>
py::array_t<double> perSample4(const PyModel& s, const Array& a, const Array& b, const Array& c,
                               const Array& d, long rows, long cols, F&& f) {
  SampleBatch batch({{&a, "q"}, {&b, "dq"}, {&c, "dqr"}, {&d, "ddqr"}}, s.model.nq());
  Data data(s.model);
  Eigen::MatrixXd M(rows, cols);
  return perSample<1>(batch, {{{rows, cols}}}, [&](const auto& x, auto out) {
    f(x[0], x[1], x[2], x[3], data, M);
    rowMajor(out[0], rows, cols) = M;
  })[0];
}

// Python-side integrator: owns a copy of the model; each call makes its own workspace, so calls
// from several threads share nothing.
struct PyIntegrator {
  PyIntegrator(const PyModel& m, const Eigen::VectorXd& p, ParameterLayout layout, double eps)
      : model(m.model), integrator(model, p, layout, eps), n(model.nq()) {}
  Model model;
  Integrator integrator;
  int n;
};

// Python-side IK solver: owns a copy of the model's chain. solve() works on a copy of the solver
// (its workspace and random generator), so calls from several threads share nothing.
struct PyIk {
  PyIk(const PyModel& m, const IkOptions& o) : solver(m.model, o), n(m.model.nq()) {}
  IkSolver solver;
  int n;
};

}  // namespace

void bindControl(py::module_& m) {
  m.def(
      "slotine_li_regressor",
      [](PyBase& b, const Array& q, const Array& dq, const Array& dqr, const Array& ddqr) {
        PyModel& s = *b.model;
        const long n = s.model.nq(), nb = b.bp.eom.size();
        SlotineLiData sl(s.model, b.bp.layout);
        return perSample4(s, q, dq, dqr, ddqr, n, nb,
                          [&](const auto& x, const auto& y, const auto& z, const auto& w,
                              Data& data, Eigen::MatrixXd& Y) {
                            slotineLiBaseRegressor(s.model, data, sl, b.bp, x, y, z, w, Y);
                          });
      },
      py::arg("base"), py::arg("q"), py::arg("dq"), py::arg("dqr"), py::arg("ddqr"),
      "Base Slotine-Li regressor Y_b (n, nb) or (m, n, nb): Y_b p_b = A ddqr + C dqr + c "
      "(+ friction).");
  m.def(
      "slotine_li_regressor_classical",
      [](PyModel& s, const Array& q, const Array& dq, const Array& dqr, const Array& ddqr,
         bool rotor, bool friction) {
        const long n = s.model.nq();
        const ParameterLayout layout = s.model.layout(rotor, friction);
        checkDriveSide(s.model, layout);
        SlotineLiData sl(s.model, layout);
        return perSample4(s, q, dq, dqr, ddqr, n, layout.size(static_cast<int>(n)),
                          [&](const auto& x, const auto& y, const auto& z, const auto& w,
                              Data& data, Eigen::MatrixXd& Y) {
                            slotineLiRegressor(s.model, data, sl, x, y, z, w, layout, Y);
                          });
      },
      py::arg("model"), py::arg("q"), py::arg("dq"), py::arg("dqr"), py::arg("ddqr"),
      py::arg("rotor") = false, py::arg("friction") = false);
  m.def(
      "coriolis_matrix",
      [](PyModel& s, const Array& q, const Array& dq, const py::object& params) {
        const long n = s.model.nq();
        ParameterLayout layout;
        const Eigen::VectorXd p = classicalParameters(s, params, layout, false);
        SlotineLiData sl(s.model, layout);
        return perSample4(
            s, q, dq, q, q, n, n,
            [&](const auto& x, const auto& y, const auto&, const auto&, Data& data,
                Eigen::MatrixXd& C) { coriolisMatrix(s.model, data, sl, x, y, p, layout, C); });
      },
      py::arg("model"), py::arg("q"), py::arg("dq"), py::arg("params") = py::none());
  py::class_<PyIntegrator>(m, "Integrator")
      .def(py::init([](const PyModel& s, const py::object& params, double coulomb_smoothing) {
             ParameterLayout layout;
             const Eigen::VectorXd p = classicalParameters(s, params, layout, false);
             return std::make_unique<PyIntegrator>(s, p, layout, coulomb_smoothing);
           }),
           py::arg("model"), py::arg("params") = py::none(), py::arg("coulomb_smoothing") = 0.0,
           "RK4 of the forward dynamics with the torque held (mindyn::Integrator) for the "
           "classical parameters `params` in any layout (default the model's).")
      .def(
          "step",
          [](PyIntegrator& g, const Eigen::VectorXd& q, const Eigen::VectorXd& dq,
             const Eigen::VectorXd& tau, double dt, int substeps) {
            Eigen::VectorXd x = vectorArg(q, g.n, "q"), v = vectorArg(dq, g.n, "dq");
            const Eigen::VectorXd t = vectorArg(tau, g.n, "tau");
            bool ok;
            {
              py::gil_scoped_release release;
              Data data(g.model);
              ok = g.integrator.step(data, x, v, t, dt, substeps);
            }
            if (!ok)
              throw py::value_error(
                  "the integration diverged (non-finite state, or a mass matrix that is not "
                  "positive definite for these parameters)");
            return py::make_tuple(x, v);
          },
          py::arg("q"), py::arg("dq"), py::arg("tau"), py::arg("dt"), py::arg("substeps") = 1,
          "Advances (q, dq) by dt seconds in `substeps` RK4 steps with tau held; returns them.")
      .def(
          "acceleration",
          [](PyIntegrator& g, const Eigen::VectorXd& q, const Eigen::VectorXd& dq,
             const Eigen::VectorXd& tau) {
            Eigen::VectorXd ddq(g.n);
            Data data(g.model);
            if (!g.integrator.acceleration(data, vectorArg(q, g.n, "q"), vectorArg(dq, g.n, "dq"),
                                           vectorArg(tau, g.n, "tau"), ddq))
              throw ModelError("the mass matrix is not positive definite for these parameters");
            return ddq;
          },
          py::arg("q"), py::arg("dq"), py::arg("tau"),
          "Forward dynamics of the simulated robot (Coulomb friction as in step).");

  py::class_<PyIk>(m, "IkSolver")
      .def(py::init([](const PyModel& s, double tolerance, int max_iterations, int max_attempts,
                       double max_time, double orientation_weight, unsigned seed) {
             if (!(tolerance > 0)) throw py::value_error("tolerance must be positive");
             if (max_iterations < 1) throw py::value_error("max_iterations must be >= 1");
             if (max_attempts < 1) throw py::value_error("max_attempts must be >= 1");
             if (!(max_time >= 0)) throw py::value_error("max_time must be >= 0 (0: no limit)");
             if (!(orientation_weight >= 0))
               throw py::value_error("orientation_weight must be >= 0");
             IkOptions o;
             o.tolerance = tolerance;
             o.max_iterations = max_iterations;
             o.max_attempts = max_attempts;
             o.max_time = max_time;
             o.orientation_weight = orientation_weight;
             o.seed = seed;
             return std::make_unique<PyIk>(s, o);
           }),
           py::arg("model"), py::arg("tolerance") = 1e-5, py::arg("max_iterations") = 100,
           py::arg("max_attempts") = 100, py::arg("max_time") = 0.005,
           py::arg("orientation_weight") = 0.3, py::arg("seed") = 42u)
      .def_property_readonly("lower", [](const PyIk& k) { return k.solver.lower(); })
      .def_property_readonly("upper", [](const PyIk& k) { return k.solver.upper(); })
      .def(
          "solve",
          [](PyIk& k, const Eigen::Matrix4d& target, const Eigen::VectorXd& q0) {
            const Eigen::VectorXd start = vectorArg(q0, k.n, "q0");
            Eigen::VectorXd q(k.n);
            IkSolver solver = k.solver;
            IkResult r;
            {
              py::gil_scoped_release release;
              r = solver.solve(isometry(target), start, q);
            }
            py::dict d;
            d["q"] = q;
            d["success"] = r.success();
            d["status"] = std::string(toString(r.status));
            d["error"] = r.error;
            d["iterations"] = r.iterations;
            d["attempts"] = r.attempts;
            return d;
          },
          py::arg("target"), py::arg("q0"))
      .def(
          "pose",
          [](PyIk& k, const Eigen::VectorXd& q) {
            Eigen::Isometry3d T;
            k.solver.kinematics().pose(vectorArg(q, k.n, "q"), T);
            return Eigen::Matrix4d(T.matrix());
          },
          py::arg("q"))
      .def(
          "jacobian",
          [](PyIk& k, const Eigen::VectorXd& q) {
            Eigen::Isometry3d T;
            Matrix6Xd J(6, k.n);
            k.solver.kinematics().poseAndJacobian(vectorArg(q, k.n, "q"), T, J);
            return Eigen::MatrixXd(J);
          },
          py::arg("q"));
}
