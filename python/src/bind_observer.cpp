// Python binding of the generalised-momentum observer (mindyn::MomentumObserver): a stateful
// object with reset / step per sample, and run over a whole log at once.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>

#include "mindyn/codegen/observer.hpp"
#include "mindyn/momentum_observer.hpp"
#include "py_args.hpp"
#include "py_types.hpp"

namespace py = pybind11;
using namespace mindyn;
using namespace mindyn::pyargs;

namespace {

// Owns what the observer refers to: the model (shared with the Python model) and a copy of the
// base parameters.
struct PyObserver {
  PyObserver(const PyBase& b, const Eigen::VectorXd& values, const Eigen::VectorXd& gains,
             double period, const Eigen::VectorXd& offset, bool held)
      : model(b.model), base(b.bp), obs(model->model, base, values, gains, period, offset, held) {}
  std::shared_ptr<PyModel> model;
  BaseParameters base;
  MomentumObserver obs;
};

py::dict countsOf(const codegen::OpCount& c) {
  py::dict d;
  d["mul"] = c.mul;
  d["add"] = c.add;
  d["trig"] = c.trig;
  d["sign"] = c.sign;
  d["tanh"] = c.tanh;
  d["exp"] = c.exp;
  return d;
}

}  // namespace

void bindObserver(py::module_& m) {
  m.def(
      "generate_observer",
      [](const std::shared_ptr<PyBase>& base_core, bool offset, const std::string& name,
         const Eigen::VectorXd& p, const Eigen::VectorXd& gains, double period, bool held,
         const std::string& lang, const std::string& header_name, bool inlineTrig) {
        using namespace mindyn::codegen;
        const Model& model = base_core->model->model;
        requireSingleDof(model, "a generated momentum observer");
        ParameterSet ps = baseParameterSet(model, base_core->bp);
        if (offset && !ps.offsets) ps = withOffsets(model, std::move(ps));
        ObserverSettings s;
        s.p = p;
        s.gains = gains;
        s.period = period;
        s.held_torque = held;
        ObserverCode c;
        {
          py::gil_scoped_release release;
          c = generateObserver(model, ps, s, name);
        }
        py::dict out;
        if (lang == "c") {
          const CFiles files =
              emitObserverC(c, header_name, inlineTrig ? CTrig::Inline : CTrig::Libm);
          out["header"] = files.header;
          out["source"] = files.source;
        } else if (lang == "st") {
          STProgram program = observerProgramST(c);
          out["text"] = writeST(program);
          out["program"] = std::move(program);
        } else {
          throw ArgumentError("lang: '" + lang + "'; expected 'c' or 'st'");
        }
        py::dict cnt;
        cnt["momentum"] = countsOf(c.core);
        cnt["step"] = countsOf(c.step);
        out["counts"] = cnt;
        out["names"] = ps.names;
        out["values"] = c.settings.p;
        out["gains"] = c.settings.gains;
        const GeometrySnap snap = geometrySnap(c.code);
        py::dict g;
        g["count"] = snap.count;
        g["largest"] = snap.largest;
        g["tolerance"] = kGeometrySnap;
        out["geometry_snap"] = g;
        return out;
      },
      py::arg("base"), py::arg("offset"), py::arg("name"), py::arg("p"), py::arg("gains"),
      py::arg("period"), py::arg("held_torque") = true, py::arg("lang") = "c",
      py::arg("header_name") = "observer.h", py::arg("inline_trig") = true,
      "A generated momentum-observer step and its operation counts.");
  py::class_<PyObserver>(m, "MomentumObserver")
      .def(py::init([](const PyBase& b, const Eigen::VectorXd& values, const Eigen::VectorXd& gains,
                       double period, const Eigen::VectorXd& offset, bool held) {
             return std::make_unique<PyObserver>(b, values, gains, period, offset, held);
           }),
           py::arg("base"), py::arg("values"), py::arg("gains"), py::arg("period"),
           py::arg("offset"), py::arg("held_torque") = true)
      .def_static("default_gain", &MomentumObserver::defaultGain, py::arg("period"))
      .def(
          "reset",
          [](PyObserver& o, const Eigen::VectorXd& q, const Eigen::VectorXd& dq,
             const Eigen::VectorXd& tau) {
            const long n = o.obs.n();
            o.obs.reset(vectorArg(q, n, "q"), vectorArg(dq, n, "dq"), vectorArg(tau, n, "tau"));
          },
          py::arg("q"), py::arg("dq"), py::arg("tau"))
      .def(
          "step",
          [](PyObserver& o, const Eigen::VectorXd& q, const Eigen::VectorXd& dq,
             const Eigen::VectorXd& tau) {
            const long n = o.obs.n();
            Eigen::VectorXd r(n);
            o.obs.step(vectorArg(q, n, "q"), vectorArg(dq, n, "dq"), vectorArg(tau, n, "tau"), r);
            return r;
          },
          py::arg("q"), py::arg("dq"), py::arg("tau"))
      .def(
          "run",
          [](PyObserver& o, const Array& q, const Array& dq, const Array& tau,
             const py::object& t) {
            const long n = o.obs.n();
            const long m = samples(q, n, "q");
            if (m < 1) throw ArgumentError("q must be a log of shape (m, n) with m >= 1");
            if (samples(dq, n, "dq") != m || samples(tau, n, "tau") != m)
              throw ArgumentError("q, dq and tau must have the same number of samples");
            Eigen::VectorXd dt;  // empty: the observer's period
            if (!t.is_none()) {
              const Array ta = t.cast<Array>();
              if (ta.ndim() != 1 || ta.shape(0) != m)
                throw ArgumentError("t has shape " + shapeOf(ta) + "; expected (" +
                                    std::to_string(m) + ",)");
              dt.resize(m);
              dt[0] = 0.0;
              for (long i = 1; i < m; ++i) dt[i] = ta.data()[i] - ta.data()[i - 1];
            }
            py::array_t<double> out({m, n});
            double* r = out.mutable_data();
            const double *pq = q.data(), *pd = dq.data(), *pt = tau.data();
            {
              py::gil_scoped_release release;
              using Map = Eigen::Map<const Eigen::VectorXd>;
              for (long i = 0; i < m; ++i) {
                Map qi(pq + i * n, n), di(pd + i * n, n), ti(pt + i * n, n);
                Eigen::Map<Eigen::VectorXd> ri(r + i * n, n);
                if (i == 0) {
                  o.obs.reset(qi, di, ti);
                  ri.setZero();
                } else if (dt.size()) {
                  o.obs.step(qi, di, ti, dt[i], ri);
                } else {
                  o.obs.step(qi, di, ti, ri);
                }
              }
            }
            return out;
          },
          py::arg("q"), py::arg("dq"), py::arg("tau"), py::arg("t") = py::none(),
          "Residual of every sample (m, n) of a log of m samples at the observer's period (or "
          "at the time stamps t): reset at sample 0 (r = 0), step at the others.")
      .def_property_readonly("momentum", [](const PyObserver& o) { return o.obs.momentum(); })
      .def_property_readonly("beta", [](const PyObserver& o) { return o.obs.beta(); })
      .def_property_readonly("residual", [](const PyObserver& o) { return o.obs.residual(); })
      .def_property_readonly("integral", [](const PyObserver& o) { return o.obs.integral(); })
      .def_property_readonly("gains", [](const PyObserver& o) { return o.obs.gains(); })
      .def_property_readonly("period", [](const PyObserver& o) { return o.obs.period(); });
}
