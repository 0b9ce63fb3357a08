// Bindings of code generation (C, Structured Text) and of the runtime base-parameter dynamics.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <optional>

#include "mindyn/base_dynamics.hpp"
#include "mindyn/codegen/controller.hpp"
#include "mindyn/codegen/emit_c.hpp"
#include "mindyn/codegen/emit_st.hpp"
#include "mindyn/codegen/newton_euler.hpp"
#include "py_args.hpp"
#include "py_types.hpp"

namespace py = pybind11;
using namespace mindyn;
using namespace mindyn::codegen;
using namespace mindyn::pyargs;

namespace {

Function functionOf(const std::string& what) {
  if (what == "inverse_dynamics" || what == "id") return Function::InverseDynamics;
  if (what == "gravity") return Function::Gravity;
  if (what == "regressor") return Function::Regressor;
  throw ArgumentError("functions: unknown function '" + what + "'");
}

py::dict snapDict(const GeometrySnap& g) {
  py::dict d;
  d["count"] = g.count;
  d["largest"] = g.largest;
  d["tolerance"] = kGeometrySnap;
  return d;
}

py::dict counts(const OpCount& c) {
  py::dict d;
  d["mul"] = c.mul;
  d["add"] = c.add;
  d["neg"] = c.neg;
  d["trig"] = c.trig;
  d["sign"] = c.sign;
  d["tanh"] = c.tanh;
  d["exp"] = c.exp;
  return d;
}

// All classical parameters of the model with these joint terms, friction in the model's
// friction model.

struct PyBaseDynamics {
  std::unique_ptr<BaseDynamics> bd;
};

}  // namespace

void bindController(py::module_& m);

void bindCodegen(py::module_& m) {
  py::class_<STVariable>(m, "STVariable",
                         "A variable of a generated FUNCTION_BLOCK: name, IEC 61131-3 elementary "
                         "type (LREAL, BOOL), array bounds (lower, upper) per dimension.")
      .def_readonly("name", &STVariable::name)
      .def_readonly("type", &STVariable::type)
      .def_readonly("dims", &STVariable::dims)
      .def_property_readonly("declared_type", &declaredType,
                             "The declaration's type (ARRAY[1..6] OF LREAL).")
      .def("__repr__", [](const STVariable& v) {
        return "STVariable('" + v.name + " : " + declaredType(v) + "')";
      });
  py::class_<STFunctionBlock>(m, "STFunctionBlock",
                              "A generated FUNCTION_BLOCK: name, inputs (VAR_INPUT), outputs "
                              "(VAR_OUTPUT), locals (VAR), a note (comment after the "
                              "declarations) and the body's statements.")
      .def_readonly("name", &STFunctionBlock::name)
      .def_readonly("inputs", &STFunctionBlock::inputs)
      .def_readonly("outputs", &STFunctionBlock::outputs)
      .def_readonly("locals", &STFunctionBlock::locals)
      .def_readonly("note", &STFunctionBlock::note)
      .def_readonly("body", &STFunctionBlock::body)
      .def("__repr__",
           [](const STFunctionBlock& b) { return "STFunctionBlock('" + b.name + "')"; });
  py::class_<STProgram>(m, "STProgram",
                        "A generated Structured Text program as blocks: the comments before "
                        "the function blocks, and the blocks.")
      .def_readonly("comments", &STProgram::comments)
      .def_readonly("blocks", &STProgram::blocks)
      .def("text", &writeST, "The Structured Text the generator writes for these blocks.")
      .def("__repr__", [](const STProgram& p) {
        return "STProgram(" + std::to_string(p.blocks.size()) + " function blocks)";
      });

  bindController(m);
  m.def(
      "generate_code",
      [](const std::shared_ptr<PyModel>& model_core, const std::shared_ptr<PyBase>& base_core,
         bool rotor, bool friction, const std::vector<std::string>& functions,
         const std::string& name, bool numeric, const std::optional<Eigen::VectorXd>& values,
         const std::string& lang, const std::string& header_name, const std::string& minimise,
         bool inlineTrig, bool offset, const std::optional<std::vector<std::string>>& formulas,
         const std::vector<int>& contacts, bool worldWrenches) {
        // Base parameters carry the model they were computed for (possibly a snapped copy).
        const Model& model = base_core ? base_core->model->model : model_core->model;
        ParameterSet ps = base_core ? baseParameterSet(model, base_core->bp)
                                    : classicalParameterSet(model, model.layout(rotor, friction));
        if (formulas) {
          if (!base_core || static_cast<long>(formulas->size()) != ps.size())
            throw ArgumentError("formulas: one per base parameter, with base parameters");
          ps.formulas = *formulas;
        }
        if (offset && !ps.offsets) ps = withOffsets(model, std::move(ps));
        std::vector<Function> fs;
        for (const auto& f : functions) fs.push_back(functionOf(f));
        // the values are read by index: a size mismatch would read past them
        if (values && values->size() != ps.size())
          throw ArgumentError("values: " + std::to_string(values->size()) + " entries; expected " +
                              std::to_string(ps.size()));
        const Objective objective =
            minimise == "additions" ? Objective::Additions : Objective::Operations;
        GeneratedCode code;
        {
          py::gil_scoped_release release;
          code = generateCode(model, ps, fs, name, numeric, values ? *values : Eigen::VectorXd(),
                              objective, Contacts{contacts, worldWrenches});
        }
        py::dict out;
        if (lang == "c") {
          const CFiles files = emitC(code, header_name, inlineTrig ? CTrig::Inline : CTrig::Libm);
          out["header"] = files.header;
          out["source"] = files.source;
        } else if (lang == "st") {
          STProgram program = programST(code);
          out["text"] = writeST(program);
          out["program"] = std::move(program);
        } else {
          throw ArgumentError("lang: '" + lang + "'; expected 'c' or 'st'");
        }
        py::dict c;
        for (const auto& f : code.functions) c[toString(f.function)] = counts(f.program.count);
        out["counts"] = c;
        out["names"] = ps.names;
        out["values"] = code.values;
        out["geometry_snap"] = snapDict(geometrySnap(code));
        return out;
      },
      py::arg("model"), py::arg("base"), py::arg("rotor") = false, py::arg("friction") = false,
      py::arg("functions") = std::vector<std::string>{"inverse_dynamics"},
      py::arg("name") = "robot", py::arg("numeric") = false,
      py::arg("values") = std::optional<Eigen::VectorXd>(), py::arg("lang") = "c",
      py::arg("header_name") = "robot.h", py::arg("minimise") = "operations",
      py::arg("inline_trig") = true, py::arg("offset") = false,
      py::arg("formulas") = std::optional<std::vector<std::string>>(),
      py::arg("contacts") = std::vector<int>(), py::arg("world_wrenches") = true,
      "Generated code and operation counts. base=None: the classical parameters; offset: a "
      "torque offset per joint after them; formulas: the text of each base parameter's "
      "formula in the header comment (default: full precision); contacts: the links (joint "
      "indices) whose wrenches a floating base's inverse dynamics takes, in world axes or "
      "(world_wrenches=False) the links' own.");

  m.def(
      "classical_parameter_names",
      [](const PyModel& model, bool rotor, bool friction, bool offset) {
        return classicalParameterSet(model.model, model.model.layout(rotor, friction, offset))
            .names;
      },
      py::arg("model"), py::arg("rotor") = false, py::arg("friction") = false,
      py::arg("offset") = false,
      "The classical parameters generated code takes (friction in the model's friction "
      "model; the torque offsets last).");

  py::class_<PyBaseDynamics, std::shared_ptr<PyBaseDynamics>>(m, "BaseDynamics")
      .def(py::init([](const PyBase& base_core, bool offset) {
             const Model& model = base_core.model->model;
             ParameterSet ps = baseParameterSet(model, base_core.bp);
             if (offset && !ps.offsets) ps = withOffsets(model, std::move(ps));
             auto out = std::make_shared<PyBaseDynamics>();
             py::gil_scoped_release release;
             out->bd = std::make_unique<BaseDynamics>(model, ps);
             return out;
           }),
           py::arg("base"), py::arg("offset") = false)
      .def_property_readonly("n", [](const PyBaseDynamics& s) { return s.bd->nq(); })
      .def_property_readonly("np", [](const PyBaseDynamics& s) { return s.bd->np(); })
      .def_property_readonly("names", [](const PyBaseDynamics& s) { return s.bd->names(); })
      .def_property_readonly(
          "geometry_snap", [](const PyBaseDynamics& s) { return snapDict(s.bd->geometrySnap()); },
          "Constants of the geometry within `tolerance` of 0 or +-1 taken as exact: how many "
          "beyond round-off (`count`) and the largest change (`largest`).")
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
            SampleBatch batch({{&q, "q"}, {&dq, "dq"}, {&ddq, "ddq"}}, n);
            auto out = batch.output({n});
            const auto p = parameterArg(pb, np, "p");
            batch.forEach([&](long i, const auto& x) {
              Eigen::Map<Eigen::VectorXd> t(out.mutable_data() + i * n, n);
              s.bd->inverseDynamics(x[0], x[1], x[2], p, t);
            });
            return out;
          },
          py::arg("q"), py::arg("dq"), py::arg("ddq"), py::arg("p"))
      .def(
          "gravity",
          [](PyBaseDynamics& s, const Array& q, const Array& pb) {
            const long n = s.bd->nq(), np = s.bd->np();
            SampleBatch batch({{&q, "q"}}, n);
            auto out = batch.output({n});
            const auto p = parameterArg(pb, np, "p");
            batch.forEach([&](long i, const auto& x) {
              Eigen::Map<Eigen::VectorXd> t(out.mutable_data() + i * n, n);
              s.bd->gravity(x[0], p, t);
            });
            return out;
          },
          py::arg("q"), py::arg("p"))
      .def(
          "regressor",
          [](PyBaseDynamics& s, const Array& q, const Array& dq, const Array& ddq) {
            const long n = s.bd->nq(), np = s.bd->np();
            SampleBatch batch({{&q, "q"}, {&dq, "dq"}, {&ddq, "ddq"}}, n);
            auto out = batch.output({n, np});
            Eigen::MatrixXd Wb(n, np);
            batch.forEach([&](long i, const auto& x) {
              s.bd->regressor(x[0], x[1], x[2], Wb);
              Eigen::Map<RowMajor>(out.mutable_data() + i * n * np, n, np) = Wb;
            });
            return out;
          },
          py::arg("q"), py::arg("dq"), py::arg("ddq"));
}

namespace {

Eigen::VectorXd settingVector(const py::dict& d, const char* key) {
  if (!d.contains(key) || d[key].is_none()) return {};
  return d[key].cast<Eigen::VectorXd>();
}

}  // namespace

void bindController(py::module_& m) {
  m.def(
      "generate_controller",
      [](const std::shared_ptr<PyBase>& base_core, bool offset, const std::string& kind,
         const std::string& name, const py::dict& settings, const std::string& lang,
         const std::string& header_name, bool inlineTrig,
         const std::shared_ptr<PyModel>& model_core) {
        if (!base_core && !model_core)
          throw ArgumentError("generate_controller: base parameters or a model");
        const Model& model = base_core ? base_core->model->model : model_core->model;
        requireSingleDof(model, "a generated controller");
        // without base parameters: all classical ones, with rotor inertia and friction
        ParameterSet ps = base_core ? baseParameterSet(model, base_core->bp)
                                    : classicalParameterSet(model, model.layout(true, true));
        if (offset && !ps.offsets) ps = withOffsets(model, std::move(ps));
        Controller k = kind == "adaptive-pd"       ? Controller::AdaptivePD
                       : kind == "computed-torque" ? Controller::ComputedTorque
                       : kind == "gravity-compensation"
                           ? Controller::GravityCompensation
                           : throw ArgumentError("kind: unknown controller '" + kind + "'");
        ControllerSettings s;
        s.kd = settingVector(settings, "kd");
        s.kp = settingVector(settings, "kp");
        s.lambda = settingVector(settings, "lambda");
        s.gamma = settingVector(settings, "gamma");
        s.p0 = settingVector(settings, "p0");
        s.p_min = settingVector(settings, "p_min");
        s.p_max = settingVector(settings, "p_max");
        s.tau_max = settingVector(settings, "tau_max");
        if (settings.contains("nu")) s.nu = settings["nu"].cast<double>();
        if (settings.contains("period")) s.period = settings["period"].cast<double>();
        ControllerCode c;
        {
          py::gil_scoped_release release;
          c = generateController(model, ps, k, s, name);
        }
        py::dict out;
        if (lang == "c") {
          const CFiles files =
              emitControllerC(c, header_name, inlineTrig ? CTrig::Inline : CTrig::Libm);
          out["header"] = files.header;
          out["source"] = files.source;
        } else if (lang == "st") {
          STProgram program = controllerProgramST(c);
          out["text"] = writeST(program);
          out["program"] = std::move(program);
        } else {
          throw ArgumentError("lang: '" + lang + "'; expected 'c' or 'st'");
        }
        py::dict cnt;
        cnt[toString(c.code.functions.front().function)] = counts(c.core);
        py::dict step = counts(c.step);
        step["div"] = c.divisions;
        cnt["step"] = step;
        out["counts"] = cnt;
        py::dict var;
        for (const auto& v : c.variants) var[toString(v.form)] = counts(v.count);
        out["variants"] = var;
        out["form"] = c.kind == Controller::AdaptivePD ? toString(c.form) : "";
        out["names"] = ps.names;
        out["values"] = c.settings.p0;
        out["geometry_snap"] = snapDict(geometrySnap(c.code));
        return out;
      },
      py::arg("base"), py::arg("offset"), py::arg("kind"), py::arg("name"), py::arg("settings"),
      py::arg("lang") = "c", py::arg("header_name") = "controller.h", py::arg("inline_trig") = true,
      py::arg("model") = std::shared_ptr<PyModel>(),
      "A generated controller step (adaptive-pd, computed-torque, gravity-compensation) and its "
      "operation counts.");
}
