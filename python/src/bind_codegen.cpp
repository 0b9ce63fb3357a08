// Bindings of code generation (C, Structured Text) and of the runtime base-parameter dynamics.
// The model and base-parameter objects of the core module are read through their Python
// attributes, so this file depends on nothing but their public interface.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <memory>
#include <optional>

#include "mindyn/base_dynamics.hpp"
#include "mindyn/codegen/emit_c.hpp"
#include "mindyn/codegen/emit_st.hpp"
#include "mindyn/codegen/newton_euler.hpp"

namespace py = pybind11;
using namespace mindyn;
using namespace mindyn::codegen;

namespace {

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

Eigen::Isometry3d isometry(const Eigen::Matrix4d& M) {
  Eigen::Isometry3d T;
  T.matrix() = M;
  return T;
}

// A C++ Model from a core Model object.
Model modelOf(const py::object& m) {
  Model model;
  model.name = m.attr("name").cast<std::string>();
  model.convention = m.attr("convention").cast<std::string>();
  const int n = m.attr("n").cast<int>();
  const auto types = m.attr("joint_types").cast<std::vector<std::string>>();
  const auto names = m.attr("joint_names").cast<std::vector<std::string>>();
  const Eigen::MatrixXd axes = m.attr("axes").cast<Eigen::MatrixXd>();
  const Eigen::MatrixXd dh = m.attr("dh").cast<Eigen::MatrixXd>();
  for (int k = 0; k < n; ++k) {
    Joint j;
    j.name = names[k];
    j.type = types[k] == "prismatic" ? JointType::Prismatic : JointType::Revolute;
    j.pre = isometry(m.attr("joint_pre")(k).cast<Eigen::Matrix4d>());
    j.post = isometry(m.attr("joint_post")(k).cast<Eigen::Matrix4d>());
    j.axis = axes.row(k).transpose();
    model.joints.push_back(j);
  }
  for (long k = 0; k < dh.rows(); ++k) model.dh.push_back({dh(k, 0), dh(k, 1), dh(k, 2), dh(k, 3)});
  model.link_names = m.attr("link_names").cast<std::vector<std::string>>();
  model.gravity = m.attr("gravity").cast<Eigen::Vector3d>();
  model.inertial = m.attr("inertial").cast<Eigen::VectorXd>();
  model.rotor_inertia = m.attr("rotor_inertia").cast<Eigen::VectorXd>();
  model.viscous = m.attr("viscous").cast<Eigen::VectorXd>();
  model.coulomb = m.attr("coulomb").cast<Eigen::VectorXd>();
  model.validate();
  return model;
}

// The base set of a core BaseParameters object, for the model it was computed for.
ParameterSet baseSetOf(const py::object& b, const Model& model) {
  ParameterSet s;
  s.layout = {b.attr("rotor").cast<bool>(), b.attr("friction").cast<bool>()};
  s.base = true;
  s.names = b.attr("names").cast<std::vector<std::string>>();
  s.formulas = b.attr("formulas").cast<std::vector<std::string>>();
  const auto pivots = b.attr("pivots").cast<std::vector<int>>();
  const Eigen::MatrixXd Y = b.attr("Y").cast<Eigen::MatrixXd>();
  const int P = s.layout.size(model.nq());
  if (Y.cols() != P) throw py::value_error("base parameters belong to another model");
  s.E = Eigen::MatrixXd::Zero(P, s.size());
  for (int i = 0; i < s.size(); ++i) s.E(pivots[i], i) = 1.0;
  s.values = Y * model.parameters(s.layout);
  return s;
}

Function functionOf(const std::string& what) {
  if (what == "inverse_dynamics" || what == "id") return Function::InverseDynamics;
  if (what == "gravity") return Function::Gravity;
  if (what == "regressor") return Function::Regressor;
  throw py::value_error("unknown function '" + what +
                        "' (inverse_dynamics or id, gravity, regressor)");
}

py::dict counts(const OpCount& c) {
  py::dict d;
  d["mul"] = c.mul;
  d["add"] = c.add;
  d["neg"] = c.neg;
  d["trig"] = c.trig;
  d["sign"] = c.sign;
  return d;
}

struct PyBaseDynamics {
  std::unique_ptr<BaseDynamics> bd;
};

long samples(const Array& a, long n, const char* name) {
  if (a.ndim() == 1 && a.shape(0) == n) return 0;
  if (a.ndim() == 2 && a.shape(1) == n) return a.shape(0);
  std::string shape = "(";
  for (long i = 0; i < a.ndim(); ++i) shape += (i ? ", " : "") + std::to_string(a.shape(i));
  throw py::value_error(std::string(name) + " has shape " + shape + (a.ndim() == 1 ? ",)" : ")") +
                        "; expected (" + std::to_string(n) + ",) or (m, " + std::to_string(n) +
                        ")");
}

void finite(const Array& a, const char* name) {
  for (long i = 0; i < static_cast<long>(a.size()); ++i)
    if (!std::isfinite(a.data()[i]))
      throw py::value_error(std::string(name) + " contains NaN or an infinite value");
}

long batchOf(const std::vector<std::pair<const Array*, const char*>>& args,
             const std::vector<long>& widths) {
  long m = -1;
  for (size_t i = 0; i < args.size(); ++i) {
    const long s = samples(*args[i].first, widths[i], args[i].second);
    finite(*args[i].first, args[i].second);
    if (m < 0)
      m = s;
    else if (s != m)
      throw py::value_error(std::string(args[i].second) +
                            ": all inputs must be single samples or batches of equal length");
  }
  return m;
}

}  // namespace

void bindCodegen(py::module_& m) {
  m.def(
      "generate_code",
      [](const py::object& model_core, const py::object& base_core, bool rotor, bool friction,
         const std::vector<std::string>& functions, const std::string& name, bool numeric,
         const std::optional<Eigen::VectorXd>& values, const std::string& lang,
         const std::string& header_name) {
        const Model model = modelOf(base_core.is_none() ? model_core : base_core.attr("model"));
        const ParameterSet ps = base_core.is_none()
                                    ? classicalParameterSet(model, {rotor, friction})
                                    : baseSetOf(base_core, model);
        std::vector<Function> fs;
        for (const auto& f : functions) fs.push_back(functionOf(f));
        if (values && values->size() != ps.size())
          throw py::value_error("got " + std::to_string(values->size()) +
                                " parameter values; expected " + std::to_string(ps.size()));
        if (values && !values->allFinite())
          throw py::value_error("parameter values contain NaN or infinity");
        GeneratedCode code;
        {
          py::gil_scoped_release release;
          code = generateCode(model, ps, fs, name, numeric, values ? *values : Eigen::VectorXd());
        }
        py::dict out;
        if (lang == "c") {
          const CFiles files = emitC(code, header_name);
          out["header"] = files.header;
          out["source"] = files.source;
        } else if (lang == "st") {
          out["text"] = emitST(code);
        } else {
          throw py::value_error("lang must be 'c' or 'st', got '" + lang + "'");
        }
        py::dict c;
        for (const auto& f : code.functions) c[toString(f.function)] = counts(f.program.count);
        out["counts"] = c;
        out["names"] = ps.names;
        out["values"] = code.values;
        return out;
      },
      py::arg("model"), py::arg("base"), py::arg("rotor") = false, py::arg("friction") = false,
      py::arg("functions") = std::vector<std::string>{"inverse_dynamics"},
      py::arg("name") = "robot", py::arg("numeric") = false,
      py::arg("values") = std::optional<Eigen::VectorXd>(), py::arg("lang") = "c",
      py::arg("header_name") = "robot.h",
      "Generated code and operation counts. base=None: the classical parameters.");

  py::class_<PyBaseDynamics, std::shared_ptr<PyBaseDynamics>>(m, "BaseDynamics")
      .def(py::init([](const py::object& base_core) {
             const Model model = modelOf(base_core.attr("model"));
             const ParameterSet ps = baseSetOf(base_core, model);
             auto out = std::make_shared<PyBaseDynamics>();
             py::gil_scoped_release release;
             out->bd = std::make_unique<BaseDynamics>(model, ps);
             return out;
           }),
           py::arg("base"))
      .def_property_readonly("n", [](const PyBaseDynamics& s) { return s.bd->nq(); })
      .def_property_readonly("np", [](const PyBaseDynamics& s) { return s.bd->np(); })
      .def_property_readonly("names", [](const PyBaseDynamics& s) { return s.bd->names(); })
      .def_property_readonly(
          "counts",
          [](const PyBaseDynamics& s) {
            py::dict d;
            for (Function f : {Function::InverseDynamics, Function::Gravity, Function::Regressor})
              d[toString(f)] = counts(s.bd->count(f));
            return d;
          })
      .def(
          "inverse_dynamics",
          [](PyBaseDynamics& s, const Array& q, const Array& dq, const Array& ddq,
             const Array& pb) {
            const long n = s.bd->nq(), np = s.bd->np();
            const long m = batchOf({{&q, "q"}, {&dq, "dq"}, {&ddq, "ddq"}}, {n, n, n});
            if (pb.ndim() != 1 || pb.shape(0) != np)
              throw py::value_error("p has the wrong shape; expected (" + std::to_string(np) +
                                    ",)");
            finite(pb, "p");
            const long rows = m == 0 ? 1 : m;
            py::array_t<double> out =
                m == 0 ? py::array_t<double>({n}) : py::array_t<double>({m, n});
            Eigen::Map<const Eigen::VectorXd> p(pb.data(), np);
            for (long i = 0; i < rows; ++i) {
              Eigen::Map<Eigen::VectorXd> t(out.mutable_data() + i * n, n);
              s.bd->inverseDynamics(Eigen::Map<const Eigen::VectorXd>(q.data() + i * n, n),
                                    Eigen::Map<const Eigen::VectorXd>(dq.data() + i * n, n),
                                    Eigen::Map<const Eigen::VectorXd>(ddq.data() + i * n, n), p, t);
            }
            return out;
          },
          py::arg("q"), py::arg("dq"), py::arg("ddq"), py::arg("p"))
      .def(
          "gravity",
          [](PyBaseDynamics& s, const Array& q, const Array& pb) {
            const long n = s.bd->nq(), np = s.bd->np();
            const long m = batchOf({{&q, "q"}}, {n});
            if (pb.ndim() != 1 || pb.shape(0) != np)
              throw py::value_error("p has the wrong shape; expected (" + std::to_string(np) +
                                    ",)");
            finite(pb, "p");
            const long rows = m == 0 ? 1 : m;
            py::array_t<double> out =
                m == 0 ? py::array_t<double>({n}) : py::array_t<double>({m, n});
            Eigen::Map<const Eigen::VectorXd> p(pb.data(), np);
            for (long i = 0; i < rows; ++i) {
              Eigen::Map<Eigen::VectorXd> t(out.mutable_data() + i * n, n);
              s.bd->gravity(Eigen::Map<const Eigen::VectorXd>(q.data() + i * n, n), p, t);
            }
            return out;
          },
          py::arg("q"), py::arg("p"))
      .def(
          "regressor",
          [](PyBaseDynamics& s, const Array& q, const Array& dq, const Array& ddq) {
            const long n = s.bd->nq(), np = s.bd->np();
            const long m = batchOf({{&q, "q"}, {&dq, "dq"}, {&ddq, "ddq"}}, {n, n, n});
            const long rows = m == 0 ? 1 : m;
            py::array_t<double> out =
                m == 0 ? py::array_t<double>({n, np}) : py::array_t<double>({m, n, np});
            Eigen::MatrixXd Wb(n, np);
            for (long i = 0; i < rows; ++i) {
              s.bd->regressor(Eigen::Map<const Eigen::VectorXd>(q.data() + i * n, n),
                              Eigen::Map<const Eigen::VectorXd>(dq.data() + i * n, n),
                              Eigen::Map<const Eigen::VectorXd>(ddq.data() + i * n, n), Wb);
              Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
                  out.mutable_data() + i * n * np, n, np) = Wb;
            }
            return out;
          },
          py::arg("q"), py::arg("dq"), py::arg("ddq"));
}
