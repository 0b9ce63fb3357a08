// Python bindings of the mindyn C++ core. Arrays in, arrays out: every per-sample function takes
// a single sample of shape (n,) or a batch of shape (m, n) and returns matching shapes.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "mindyn/base_parameters.hpp"
#include "mindyn/data.hpp"
#include "mindyn/description.hpp"
#include "mindyn/dynamics.hpp"
#include "mindyn/ik.hpp"
#include "mindyn/kinematics.hpp"
#include "mindyn/model.hpp"
#include "mindyn/momentum.hpp"
#include "mindyn/projection.hpp"
#include "mindyn/recursive_base.hpp"
#include "mindyn/spatial.hpp"
#include "mindyn/urdf.hpp"
#include "py_args.hpp"
#include "py_types.hpp"

namespace py = pybind11;
using namespace mindyn;
using namespace mindyn::pyargs;

void bindControl(py::module_& m);
void bindObserver(py::module_& m);
void bindMultibody(py::module_& m);

namespace {

Eigen::Matrix4d toMatrix(const Eigen::Isometry3d& T) { return T.matrix(); }

py::dict setDict(const BaseSet& set, const std::vector<std::string>& names) {
  const RankDecision& d = set.decision;
  py::dict out;
  out["n"] = set.size();
  out["names"] = set.names;
  // Y and the formulas, large on long chains and trees, come from set_matrix, set_rows and
  // set_formulas, on request.
  out["pivots"] = d.pivots;
  out["pivot_size"] = d.pivot_size;
  std::vector<std::string> zero, dep;
  for (int c : d.zero) zero.push_back(names[c]);
  for (int c : d.dependent) dep.push_back(names[c]);
  out["no_effect"] = zero;
  out["regrouped"] = dep;
  out["residual"] = d.residual;
  py::dict margin;
  margin["tolerance"] = d.tolerance;
  margin["smallest_kept"] = d.smallest_kept;
  margin["largest_dropped"] = d.largest_dropped;
  margin["rank_at_looser_tolerance"] = d.rank_looser;
  margin["rank_at_tighter_tolerance"] = d.rank_tighter;
  margin["looser_tolerance"] = d.tolerance * 1e4;
  margin["tighter_tolerance"] = d.tolerance * 1e-3;
  margin["weakest_kept_for_its_kind"] = d.weakest_kept;
  margin["zero_threshold"] = d.zero_threshold;
  margin["largest_zeroed"] = d.largest_zeroed;
  margin["near_degenerate"] = d.near_degenerate;
  std::vector<std::string> undecided;
  for (int c : d.undecided) undecided.push_back(names[c]);
  margin["decided_by_tolerance"] = undecided;
  margin["fit_residual"] = d.fit_residual;
  margin["consistency"] = d.consistency;
  out["margin"] = margin;
  return out;
}

const BaseSet& setOf(const BaseParameters& bp, const std::string& name) {
  if (name == "lagrangian") return bp.lagrangian;
  if (name == "energy") return bp.energy;
  if (name == "eom") return bp.eom;
  throw ArgumentError("set must be 'lagrangian', 'energy' or 'eom', got '" + name + "'");
}

py::dict limitsDict(const JointLimits& l) {
  py::dict d;
  d["lower"] = l.lower;
  d["upper"] = l.upper;
  d["velocity"] = l.velocity;
  d["acceleration"] = l.acceleration;
  d["effort"] = l.effort;
  return d;
}

}  // namespace

void bindCodegen(pybind11::module_& m);
void bindCsv(pybind11::module_& m);
void bindFilter(pybind11::module_& m);

PYBIND11_MODULE(_core, m) {
  m.doc() = "mindyn C++ core: models, linear-in-parameters dynamics, kinematics";

  // mindyn.Error: the base of every error mindyn raises for its input (the Python ones derive
  // from it too); each keeps the standard base it had, ValueError or FileNotFoundError.
  auto error = py::reinterpret_steal<py::object>(PyErr_NewExceptionWithDoc(
      "mindyn._core.Error", "Base class of the errors mindyn raises.", nullptr, nullptr));
  if (!error) throw py::error_already_set();
  m.attr("Error") = error;
  py::register_exception<ModelError>(m, "ModelError",
                                     py::make_tuple(error, py::handle(PyExc_ValueError)));
  // mindyn.ArgumentError: an argument of a wrong type or value (mindyn/_args.py raises it for
  // the public functions, the bindings' guards for direct calls).
  py::register_exception<ArgumentError>(
      m, "ArgumentError",
      py::make_tuple(error, py::handle(PyExc_ValueError), py::handle(PyExc_TypeError)));
  py::register_exception<FileError>(m, "RobotFileNotFoundError",
                                    py::make_tuple(error, py::handle(PyExc_FileNotFoundError)));
  // The prefix of the torque offsets' parameter names (Off1, ...), as the layout spells it.
  m.attr("OFFSET_PREFIX") = std::string(kOffsetPrefix);

  py::class_<PyModel, std::shared_ptr<PyModel>>(m, "Model")
      .def_property_readonly("n", [](const PyModel& s) { return s.model.nq(); })
      .def_property_readonly("nq", [](const PyModel& s) { return s.model.configSize(); })
      .def_property_readonly("nv", [](const PyModel& s) { return s.model.velocitySize(); })
      .def_property_readonly("single_dof", [](const PyModel& s) { return s.model.singleDof(); })
      .def_property_readonly("name", [](const PyModel& s) { return s.model.name; })
      .def_property_readonly("source", [](const PyModel& s) { return s.model.source; })
      .def_property_readonly("convention", [](const PyModel& s) { return s.model.convention; })
      .def_property_readonly("notes", [](const PyModel& s) { return s.model.notes; })
      .def_property_readonly("unread_transmissions",
                             [](const PyModel& s) {
                               py::list out;
                               for (const TransmissionGroup& g : s.model.unread_transmissions) {
                                 py::dict d;
                                 d["name"] = g.name;
                                 d["type"] = g.type;
                                 d["joints"] = g.joints;
                                 d["line"] = g.line;
                                 out.append(d);
                               }
                               return out;
                             })
      .def_property_readonly("synthetic_inertia",
                             [](const PyModel& s) { return s.model.synthetic_inertia; })
      .def_property_readonly("link_names", [](const PyModel& s) { return s.model.link_names; })
      .def_property_readonly("parents",
                             [](const PyModel& s) {
                               std::vector<int> v;
                               for (int k = 0; k < s.model.nq(); ++k)
                                 v.push_back(s.model.parent(k));
                               return v;
                             })
      .def_property_readonly("joint_names",
                             [](const PyModel& s) {
                               std::vector<std::string> v;
                               for (const auto& j : s.model.joints) v.push_back(j.name);
                               return v;
                             })
      .def_property_readonly("joint_types",
                             [](const PyModel& s) {
                               std::vector<std::string> v;
                               for (const auto& j : s.model.joints) v.push_back(toString(j.type));
                               return v;
                             })
      .def_property_readonly("axes",
                             [](const PyModel& s) {
                               Eigen::MatrixXd a(s.model.nq(), 3);
                               for (int k = 0; k < s.model.nq(); ++k)
                                 a.row(k) = s.model.joints[k].axis.transpose();
                               return a;
                             })
      .def(
          "joint_pre", [](const PyModel& s, int k) { return toMatrix(s.model.joints.at(k).pre); },
          "4x4 fixed transform from link k-1 to the frame of joint k (0-based k).")
      .def(
          "joint_post", [](const PyModel& s, int k) { return toMatrix(s.model.joints.at(k).post); },
          "4x4 fixed transform from the moved joint frame to link k (0-based k).")
      .def("joint_transform", [](const PyModel& s, int k,
                                 double q) { return toMatrix(s.model.joints.at(k).transform(q)); })
      .def_property_readonly("limits",
                             [](const PyModel& s) {
                               py::list l;
                               for (const auto& j : s.model.joints) l.append(limitsDict(j.limits));
                               return l;
                             })
      .def_property_readonly("drives",
                             [](const PyModel& s) {
                               py::list l;
                               for (const auto& j : s.model.joints) {
                                 py::dict d;
                                 d["rated_torque"] = j.drive.rated_torque;
                                 d["gear_ratio"] = j.drive.gear_ratio;
                                 d["torque_constant"] = j.drive.torque_constant;
                                 l.append(d);
                               }
                               return l;
                             })
      .def_property_readonly(
          "transmission",
          [](const PyModel& s) {
            const Transmission& t = s.model.transmission;
            py::dict d;
            d["format"] = t.format;
            d["T"] = Eigen::MatrixXd(t.T.rows() == 0 ? Eigen::MatrixXd(0, s.model.nq()) : t.T);
            d["offset"] = Eigen::VectorXd(t.offset);
            d["motors"] = t.motors;
            d["types"] = t.types;
            d["torque_constant"] = Eigen::VectorXd(t.torque_constant);
            py::list groups;
            for (const TransmissionGroup& g : t.groups) {
              py::dict e;
              e["name"] = g.name;
              e["type"] = g.type;
              e["joints"] = g.joints;
              e["actuators"] = g.actuators;
              e["actuator_reduction"] = g.actuator_reduction;
              e["joint_reduction"] = g.joint_reduction;
              e["joint_offset"] = g.joint_offset;
              groups.append(e);
            }
            d["groups"] = groups;
            return d;
          })
      .def_property_readonly(
          "drive_side",
          [](const PyModel& s) { return std::string(s.model.motorSide() ? "motor" : "joint"); })
      .def(
          "with_drive_side",
          [](const PyModel& s, const std::string& side) {
            if (side != "motor" && side != "joint")
              throw ArgumentError("drive side must be 'motor' or 'joint', not '" + side + "'");
            if (side == "motor" && s.model.transmission.empty())
              throw ModelError(s.model.name +
                               " declares no transmissions: its rotor inertia and friction can "
                               "only act on the joints");
            if (side == "motor" && s.model.transmission.nm() != s.model.nq())
              throw ModelError(s.model.name + " has " + std::to_string(s.model.transmission.nm()) +
                               " motors for " + std::to_string(s.model.nq()) +
                               " joints: rotor inertia and friction on the motors need one "
                               "motor per joint; they can only act on the joints");
            Model copy = s.model;
            copy.drive_terms_on_motors = side == "motor";
            return std::make_shared<PyModel>(std::move(copy));
          },
          py::arg("side"),
          "A new model whose rotor inertia and friction act on the motors ('motor') or on the "
          "joints ('joint'); this one is unchanged.")
      .def(
          "with_drive_of",
          [](const PyModel& s, const PyModel& other) {
            if (other.model.joints.size() != s.model.joints.size())
              throw ModelError(s.model.name + " has " + std::to_string(s.model.joints.size()) +
                               " joints, " + other.model.name + " " +
                               std::to_string(other.model.joints.size()) +
                               ": the transmissions of one do not fit the other");
            Model copy = s.model;
            copy.transmission = other.model.transmission;
            copy.transmission.validate(copy.joints, copy.name);
            copy.drive_terms_on_motors = other.model.drive_terms_on_motors;
            copy.friction_model = other.model.friction_model;
            return std::make_shared<PyModel>(std::move(copy));
          },
          py::arg("other"),
          "A new model with the joints of this one and the transmissions, drive side and "
          "friction model of `other` (a model of as many joints); this one is unchanged.")
      .def(
          "with_transmission",
          [](const PyModel& s, const Eigen::MatrixXd& T, const std::vector<std::string>& motors,
             const std::vector<std::string>& types, const std::string& format) {
            if (static_cast<Eigen::Index>(motors.size()) != T.rows() ||
                types.size() != motors.size())
              throw ArgumentError("with_transmission: " + std::to_string(motors.size()) +
                                  " motors and " + std::to_string(types.size()) +
                                  " types for a matrix of " + std::to_string(T.rows()) + " rows");
            Model copy = s.model;
            Transmission t;
            t.format = format;
            t.T = T;
            t.offset = Eigen::VectorXd::Zero(T.rows());
            t.motors = motors;
            t.types = types;
            t.torque_constant =
                Eigen::VectorXd::Constant(T.rows(), std::numeric_limits<double>::quiet_NaN());
            t.validate(copy.joints, copy.name);
            copy.transmission = std::move(t);
            copy.drive_terms_on_motors = true;
            copy.validate();
            return std::make_shared<PyModel>(std::move(copy));
          },
          py::kw_only(), py::arg("T"), py::arg("motors"), py::arg("types"), py::arg("format"),
          "A new model with the transmission q_m = T q (no offsets, no torque constants) of the "
          "named motors, each of its `types`, and the rotor inertia and friction on them; this "
          "one is unchanged.")
      .def(
          "with_joint_terms",
          [](const PyModel& s, const std::optional<Eigen::VectorXd>& rotor,
             const std::optional<Eigen::VectorXd>& viscous,
             const std::optional<Eigen::VectorXd>& coulomb,
             const std::optional<Eigen::VectorXd>& motor_rotor,
             const std::optional<Eigen::VectorXd>& motor_viscous,
             const std::optional<Eigen::VectorXd>& motor_coulomb,
             const std::optional<Eigen::VectorXd>& motor_third,
             const std::optional<Eigen::VectorXd>& offset) {
            Model copy = s.model;
            const auto set = [](const std::optional<Eigen::VectorXd>& v, Eigen::VectorXd& to,
                                long size, const char* what) {
              if (!v) return;
              if (v->size() != size)
                throw ArgumentError(std::string(what) + " has " + std::to_string(v->size()) +
                                    " entries; expected " + std::to_string(size));
              to = *v;
            };
            const long n = copy.nq(), m = copy.transmission.nm();
            set(rotor, copy.rotor_inertia, n, "rotor");
            set(viscous, copy.viscous, n, "viscous");
            set(coulomb, copy.coulomb, n, "coulomb");
            set(motor_rotor, copy.transmission.rotor_inertia, m, "motor_rotor");
            set(motor_viscous, copy.transmission.viscous, m, "motor_viscous");
            set(motor_coulomb, copy.transmission.coulomb, m, "motor_coulomb");
            set(motor_third, copy.transmission.third_friction, m, "motor_third");
            set(offset, copy.torque_offset, n, "offset");
            copy.validate();
            return std::make_shared<PyModel>(std::move(copy));
          },
          py::kw_only(), py::arg("rotor") = py::none(), py::arg("viscous") = py::none(),
          py::arg("coulomb") = py::none(), py::arg("motor_rotor") = py::none(),
          py::arg("motor_viscous") = py::none(), py::arg("motor_coulomb") = py::none(),
          py::arg("motor_third") = py::none(), py::arg("offset") = py::none(),
          "A new model with the given joint-side rotor inertia, viscous and Coulomb friction (n "
          "each), the motors' own (n_m each, as a YAML table's transmissions give them; NaN: "
          "none, derived from the joint's), the motors' own third friction parameters (n_m, NaN: "
          "none) and torque offsets (n); a term not given is kept. This one is unchanged.")
      .def_property_readonly("torque_offset",
                             [](const PyModel& s) {
                               return s.model.torque_offset.size() == s.model.nq()
                                          ? Eigen::VectorXd(s.model.torque_offset)
                                          : Eigen::VectorXd(Eigen::VectorXd::Zero(s.model.nq()));
                             })
      .def_property_readonly("friction_model",
                             [](const PyModel& s) {
                               const FrictionModel& f = s.model.friction_model;
                               py::dict d;
                               d["kind"] = toString(f.kind);
                               d["velocity"] = Eigen::VectorXd(f.velocity);
                               return d;
                             })
      .def(
          "with_friction_model",
          [](const PyModel& s, const std::string& kind, const Eigen::VectorXd& velocity) {
            FrictionModel f;
            f.kind = frictionKindOf(kind);
            f.velocity = velocity;
            f.validate(s.model.nq());
            Model copy = s.model;
            copy.friction_model = f;
            return std::make_shared<PyModel>(std::move(copy));
          },
          py::arg("kind"), py::arg("velocity") = Eigen::VectorXd(),
          "A new model with this friction model (coulomb | asymmetric | smooth | stribeck; "
          "smooth and stribeck need a positive velocity per slot); this one is unchanged.")
      .def_property_readonly("dh",
                             [](const PyModel& s) {
                               Eigen::MatrixXd d(s.model.dh.size(), 4);
                               for (size_t k = 0; k < s.model.dh.size(); ++k)
                                 d.row(k) << s.model.dh[k].a, s.model.dh[k].alpha, s.model.dh[k].d,
                                     s.model.dh[k].theta;
                               return d;
                             })
      .def_property_readonly("gravity",
                             [](const PyModel& s) { return Eigen::Vector3d(s.model.gravity); })
      .def(
          "with_gravity",
          [](const PyModel& s, const Eigen::Vector3d& g) {
            Model copy = s.model;
            copy.gravity = g;
            copy.validate();  // the bound on every number holds for gravity too
            return std::make_shared<PyModel>(std::move(copy));
          },
          py::arg("gravity"),
          "A new model, the same but for its gravity vector (base frame, m/s^2); this one is "
          "unchanged.")
      .def(
          "with_spherical",
          [](const PyModel& s, const std::vector<std::string>& names) {
            Model copy = s.model;
            for (const std::string& name : names) {
              auto j = std::find_if(copy.joints.begin(), copy.joints.end(),
                                    [&](const Joint& x) { return x.name == name; });
              if (j == copy.joints.end() || j->type != JointType::FreeFlyer)
                throw ArgumentError("with_spherical: '" + name + "' is no floating joint of " +
                                    copy.name);
              j->type = JointType::Spherical;  // its rotation about the same frame's origin
            }
            copy.validate();
            return std::make_shared<PyModel>(std::move(copy));
          },
          py::arg("names"),
          "A new model, the same but with the named floating (free-flyer) joints made "
          "spherical: the rotation about the same joint frame's origin, without translation (a "
          "ball joint, which URDF text cannot carry); this one is unchanged.")
      .def_property_readonly("tool", [](const PyModel& s) { return toMatrix(s.model.tool); })
      .def_property(
          "inertial", [](const PyModel& s) { return Eigen::VectorXd(s.model.inertial); },
          [](PyModel& s, const Eigen::VectorXd& v) {
            if (v.size() != s.model.inertial.size())
              throw ArgumentError("inertial must have " + std::to_string(s.model.inertial.size()) +
                                  " entries");
            s.model.inertial = v;
          })
      .def_property(
          "rotor_inertia", [](const PyModel& s) { return Eigen::VectorXd(s.model.rotor_inertia); },
          [](PyModel& s, const Eigen::VectorXd& v) {
            if (v.size() != s.model.nq()) throw ArgumentError("rotor_inertia must have n entries");
            s.model.rotor_inertia = v;
          })
      .def_property(
          "viscous", [](const PyModel& s) { return Eigen::VectorXd(s.model.viscous); },
          [](PyModel& s, const Eigen::VectorXd& v) {
            if (v.size() != s.model.nq()) throw ArgumentError("viscous must have n entries");
            s.model.viscous = v;
          })
      .def_property(
          "coulomb", [](const PyModel& s) { return Eigen::VectorXd(s.model.coulomb); },
          [](PyModel& s, const Eigen::VectorXd& v) {
            if (v.size() != s.model.nq()) throw ArgumentError("coulomb must have n entries");
            s.model.coulomb = v;
          })
      .def_property(
          "third_friction",
          [](const PyModel& s) {
            return s.model.third_friction.size() == s.model.nq()
                       ? Eigen::VectorXd(s.model.third_friction)
                       : Eigen::VectorXd(Eigen::VectorXd::Zero(s.model.nq()));
          },
          [](PyModel& s, const Eigen::VectorXd& v) {
            if (v.size() != s.model.nq()) throw ArgumentError("third_friction must have n entries");
            s.model.third_friction = v;
          })
      .def(
          "parameter_names",
          [](const PyModel& s, bool rotor, bool friction, bool offset) {
            return s.model.parameterNames(s.model.layout(rotor, friction, offset));
          },
          py::arg("rotor") = false, py::arg("friction") = false, py::arg("offset") = false)
      .def(
          "parameters",
          [](const PyModel& s, bool rotor, bool friction, bool offset) {
            return s.model.parameters(s.model.layout(rotor, friction, offset));
          },
          py::arg("rotor") = false, py::arg("friction") = false, py::arg("offset") = false)
      .def(
          "inverse_dynamics",
          [](PyModel& s, const Array& q, const Array& dq, const Array& ddq,
             const py::object& params) {
            ParameterLayout layout;
            const Eigen::VectorXd p = classicalParameters(s, params, layout, false);
            const long n = s.model.nq();
            SampleBatch batch({{&q, "q"}, {&dq, "dq"}, {&ddq, "ddq"}}, n);
            Data data(s.model);
            return perSample<1>(batch, {{{n}}}, [&](const auto& x, auto out) {
              inverseDynamics(s.model, data, x[0], x[1], x[2], p, layout, vectorAt(out[0], n));
            })[0];
          },
          py::arg("q"), py::arg("dq"), py::arg("ddq"), py::arg("params") = py::none())
      .def(
          "gravity_torque",
          [](PyModel& s, const Array& q, const py::object& params) {
            ParameterLayout layout;
            const Eigen::VectorXd p = classicalParameters(s, params, layout, false);
            const long n = s.model.nq();
            SampleBatch batch({{&q, "q"}}, n);
            Data data(s.model);
            return perSample<1>(batch, {{{n}}}, [&](const auto& x, auto out) {
              gravityTorque(s.model, data, x[0], p, layout, vectorAt(out[0], n));
            })[0];
          },
          py::arg("q"), py::arg("params") = py::none())
      .def(
          "forward_dynamics",
          [](PyModel& s, const Array& q, const Array& dq, const Array& tau,
             const py::object& params) {
            ParameterLayout layout;
            const Eigen::VectorXd p = classicalParameters(s, params, layout, false);
            const long n = s.model.nq();
            SampleBatch batch({{&q, "q"}, {&dq, "dq"}, {&tau, "tau"}}, n);
            Data data(s.model);
            return perSample<1>(batch, {{{n}}}, [&](const auto& x, auto out) {
              if (!forwardDynamics(s.model, data, x[0], x[1], x[2], p, layout, vectorAt(out[0], n)))
                throw ModelError("the mass matrix is not positive definite for these parameters");
            })[0];
          },
          py::arg("q"), py::arg("dq"), py::arg("tau"), py::arg("params") = py::none())
      .def(
          "regressor",
          [](PyModel& s, const Array& q, const Array& dq, const Array& ddq, bool rotor,
             bool friction, bool offset) {
            const long n = s.model.nq();
            SampleBatch batch({{&q, "q"}, {&dq, "dq"}, {&ddq, "ddq"}}, n);
            const ParameterLayout layout = s.model.layout(rotor, friction, offset);
            checkDriveSide(s.model, layout);
            const long P = layout.size(static_cast<int>(n));
            Data data(s.model);
            Eigen::MatrixXd W(n, P);
            return perSample<1>(batch, {{{n, P}}}, [&](const auto& x, auto out) {
              regressor(s.model, data, x[0], x[1], x[2], layout, W);
              rowMajor(out[0], n, P) = W;
            })[0];
          },
          py::arg("q"), py::arg("dq"), py::arg("ddq"), py::arg("rotor") = false,
          py::arg("friction") = false, py::arg("offset") = false)
      .def(
          "energy_regressors",
          [](PyModel& s, const Array& q, const Array& dq, bool rotor, bool friction, bool offset) {
            const long n = s.model.nq();
            SampleBatch batch({{&q, "q"}, {&dq, "dq"}}, n);
            const ParameterLayout layout = s.model.layout(rotor, friction, offset);
            checkDriveSide(s.model, layout);
            const long P = layout.size(static_cast<int>(n));
            Data data(s.model);
            auto [wk, wp] = perSample<2>(batch, {{{P}, {P}}}, [&](const auto& x, auto out) {
              energyRegressors(s.model, data, x[0], x[1], layout, vectorAt(out[0], P),
                               vectorAt(out[1], P));
            });
            return py::make_tuple(wk, wp);
          },
          py::arg("q"), py::arg("dq"), py::arg("rotor") = false, py::arg("friction") = false,
          py::arg("offset") = false)
      .def(
          "momentum_regressors",
          [](PyModel& s, const Array& q, const Array& dq, bool rotor, bool friction, bool offset) {
            const long n = s.model.nq();
            SampleBatch batch({{&q, "q"}, {&dq, "dq"}}, n);
            const ParameterLayout layout = s.model.layout(rotor, friction, offset);
            checkDriveSide(s.model, layout);
            const long P = layout.size(static_cast<int>(n));
            Data data(s.model);
            Eigen::MatrixXd Wp(n, P), Wl(n, P);
            auto [wp, wl] = perSample<2>(batch, {{{n, P}, {n, P}}}, [&](const auto& x, auto out) {
              momentumRegressors(s.model, data, x[0], x[1], layout, Wp, Wl);
              rowMajor(out[0], n, P) = Wp;
              rowMajor(out[1], n, P) = Wl;
            });
            return py::make_tuple(wp, wl);
          },
          py::arg("q"), py::arg("dq"), py::arg("rotor") = false, py::arg("friction") = false,
          py::arg("offset") = false)
      .def(
          "friction_shapes",
          [](PyModel& s, const Array& dq) {
            const long n = s.model.nq();
            const int c = s.model.friction_model.columns();
            SampleBatch batch({{&dq, "dq"}}, n);
            return perSample<1>(batch, {{{n, c}}}, [&](const auto& x, auto out) {
              for (int k = 0; k < n; ++k) {
                double phi[3] = {0.0, 0.0, 0.0};
                slotFrictionShapes(s.model, k, x[0][k], phi);
                for (int i = 0; i < c; ++i) out[0][k * c + i] = phi[i];
              }
            })[0];
          },
          py::arg("dq"),
          "The friction columns of each slot at the slot velocities `dq`, (n, c) or (m, n, c).")
      .def(
          "energies",
          [](PyModel& s, const Array& q, const Array& dq, const py::object& params) {
            const long n = s.model.nq();
            SampleBatch batch({{&q, "q"}, {&dq, "dq"}}, n);
            ParameterLayout layout;
            const Eigen::VectorXd p = classicalParameters(s, params, layout, false);
            Data data(s.model);
            auto [K, P] = perSample<2>(batch, {{{}, {}}}, [&](const auto& x, auto out) {
              *out[0] = kineticEnergy(s.model, data, x[0], x[1], p, layout);
              *out[1] = potentialEnergy(s.model, data, x[0], p, layout);
            });
            if (batch.single()) return py::object(py::make_tuple(*K.data(), *P.data()));
            return py::object(py::make_tuple(K, P));
          },
          py::arg("q"), py::arg("dq"), py::arg("params") = py::none())
      .def(
          "mass_matrix",
          [](PyModel& s, const Array& q, const py::object& params) {
            const long n = s.model.nq();
            SampleBatch batch({{&q, "q"}}, n);
            ParameterLayout layout;
            const Eigen::VectorXd p = classicalParameters(s, params, layout, false);
            Data data(s.model);
            Eigen::MatrixXd M(n, n);
            return perSample<1>(batch, {{{n, n}}}, [&](const auto& x, auto out) {
              massMatrix(s.model, data, x[0], p, layout, M);
              rowMajor(out[0], n, n) = M;
            })[0];
          },
          py::arg("q"), py::arg("params") = py::none());

  // Kinematics of any model, chain or tree, from the kinematic pass of the dynamics (the KDL
  // class below holds chains only).
  const auto requireSize = [](const Eigen::VectorXd& q, int n, const char* name) {
    if (q.size() != n)
      throw ArgumentError(std::string(name) + " has " + std::to_string(q.size()) +
                          " entries; the model has " + std::to_string(n) + " joints");
  };
  m.def(
      "link_poses",
      [requireSize](const PyModel& s, const Eigen::VectorXd& q) {
        requireSize(q, s.model.nq(), "q");
        Data data(s.model);
        forwardKinematics(s.model, data, q);
        std::vector<Eigen::Matrix4d> poses(static_cast<size_t>(s.model.nq()));
        for (int k = 0; k < s.model.nq(); ++k) {
          Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
          T.linear() = data.R0[k];
          T.translation() = data.p0[k];
          poses[static_cast<size_t>(k)] = T.matrix();
        }
        return poses;
      },
      py::arg("model"), py::arg("q"));
  m.def(
      "tool_jacobian",
      [requireSize](const PyModel& s, const Eigen::VectorXd& q) {
        requireSize(q, s.model.nq(), "q");
        ChainKinematics kin(s.model);
        Eigen::Isometry3d T;
        Matrix6Xd J(6, s.model.nq());
        kin.poseAndJacobian(q, T, J);
        return Eigen::MatrixXd(J);
      },
      py::arg("model"), py::arg("q"));

  py::class_<Kinematics>(m, "Kinematics")
      .def(py::init([](const PyModel& s) { return std::make_unique<Kinematics>(s.model); }))
      .def(
          "pose",
          [](Kinematics& k, const Eigen::VectorXd& q, int link) {
            return toMatrix(k.pose(q, link));
          },
          py::arg("q"), py::arg("link") = -1)
      .def("jacobian",
           [](Kinematics& k, const Eigen::VectorXd& q) { return Eigen::MatrixXd(k.jacobian(q)); });

  py::class_<PyBase, std::shared_ptr<PyBase>>(m, "BaseParameters")
      .def_property_readonly("n", [](const PyBase& b) { return b.bp.eom.size(); })
      .def_property_readonly("names", [](const PyBase& b) { return b.bp.eom.names; })
      .def_property_readonly(
          "formulas", [](const PyBase& b) { return b.bp.eom.formulas(b.bp.classical_names); })
      .def_property_readonly("Y",
                             [](const PyBase& b) { return Eigen::MatrixXd(b.bp.eom.decision.Y); })
      .def(
          "set_matrix",
          [](const PyBase& b, const std::string& set) {
            return Eigen::MatrixXd(setOf(b.bp, set).decision.Y);
          },
          py::arg("set"), "Y of a set ('lagrangian', 'energy', 'eom'), dense.")
      .def(
          "set_rows",
          [](const PyBase& b, const std::string& set, long first, long count) {
            const Eigen::SparseMatrix<double>& Y = setOf(b.bp, set).decision.Y;
            first = std::clamp<long>(first, 0, Y.rows());
            count = std::clamp<long>(count, 0, Y.rows() - first);
            std::vector<int> cols;  // the columns with an entry in these rows
            for (int c = 0; c < Y.cols(); ++c)
              for (Eigen::SparseMatrix<double>::InnerIterator it(Y, c); it; ++it)
                if (it.row() >= first && it.row() < first + count) {
                  cols.push_back(c);
                  break;
                }
            using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
            RowMajor out = RowMajor::Zero(count, static_cast<long>(cols.size()));
            for (std::size_t i = 0; i < cols.size(); ++i)
              for (Eigen::SparseMatrix<double>::InnerIterator it(Y, cols[i]); it; ++it)
                if (it.row() >= first && it.row() < first + count)
                  out(it.row() - first, static_cast<long>(i)) = it.value();
            return py::make_tuple(out, cols);
          },
          py::arg("set"), py::arg("first"), py::arg("count"),
          "Rows first .. first + count - 1 of a set's Y on the columns where they have entries: "
          "(dense rows, those columns).")
      .def(
          "set_formulas",
          [](const PyBase& b, const std::string& set) {
            return setOf(b.bp, set).formulas(b.bp.classical_names);
          },
          py::arg("set"), "A set's formulas at full precision.")
      .def_property_readonly("pivots", [](const PyBase& b) { return b.bp.eom.decision.pivots; })
      .def_property_readonly("classical_names",
                             [](const PyBase& b) { return b.bp.classical_names; })
      .def_property_readonly("rotor", [](const PyBase& b) { return b.bp.layout.rotor; })
      .def_property_readonly("friction", [](const PyBase& b) { return b.bp.layout.friction; })
      .def_property_readonly("offset", [](const PyBase& b) { return b.bp.layout.offset; })
      .def(
          "with_friction_velocity",
          [](const PyBase& b, const Eigen::VectorXd& velocity) {
            // The friction columns are base parameters of their own: the set does not depend
            // on the velocity scale, only the regressor's columns do.
            Model copy = b.model->model;
            copy.friction_model.velocity = velocity;
            copy.friction_model.validate(copy.nq());
            auto out = std::make_shared<PyBase>(b);
            out->model = std::make_shared<PyModel>(std::move(copy));
            return out;
          },
          py::arg("velocity"),
          "The same base set for the model with its friction model's velocity scale replaced.")
      .def_property_readonly("method",
                             [](const PyBase& b) {
                               switch (b.bp.method) {
                                 case BaseMethod::Projection:
                                   return std::string("projection");
                                 case BaseMethod::Recursive:
                                   return std::string("recursive");
                                 default:
                                   return std::string("numerical");
                               }
                             })
      .def_property_readonly(
          "lagrangian",
          [](const PyBase& b) { return setDict(b.bp.lagrangian, b.bp.classical_names); })
      .def_property_readonly(
          "energy", [](const PyBase& b) { return setDict(b.bp.energy, b.bp.classical_names); })
      .def_property_readonly(
          "eom", [](const PyBase& b) { return setDict(b.bp.eom, b.bp.classical_names); })
      .def_property_readonly("lagrangian_equals_energy",
                             [](const PyBase& b) { return b.bp.lagrangian_equals_energy; })
      .def_property_readonly("lagrangian_equals_eom",
                             [](const PyBase& b) { return b.bp.lagrangian_equals_eom; })
      .def_property_readonly("basis_rows", [](const PyBase& b) { return b.bp.basis_rows; })
      .def_property_readonly("terms_formed", [](const PyBase& b) { return b.bp.terms_formed; })
      .def_property_readonly("seconds", [](const PyBase& b) { return b.bp.seconds; })
      .def_property_readonly("snapped", [](const PyBase& b) { return b.snapped; })
      .def_property_readonly("snappable", [](const PyBase& b) { return b.bp.snappable; })
      .def_property_readonly("model", [](const PyBase& b) { return b.model; })
      .def("values", [](const PyBase& b, const Eigen::VectorXd& pi) { return b.bp.values(pi); })
      .def("embed", [](const PyBase& b, const Eigen::VectorXd& pb) { return b.bp.embed(pb); })
      .def(
          "regressor",
          [](PyBase& b, const Array& q, const Array& dq, const Array& ddq) {
            PyModel& s = *b.model;
            const long n = s.model.nq();
            SampleBatch batch({{&q, "q"}, {&dq, "dq"}, {&ddq, "ddq"}}, n);
            const long nb = b.bp.eom.size();
            Data data(s.model);
            Eigen::MatrixXd W(n, b.bp.layout.size(static_cast<int>(n))), Wb(n, nb);
            return perSample<1>(batch, {{{n, nb}}}, [&](const auto& x, auto out) {
              baseRegressor(s.model, data, b.bp, x[0], x[1], x[2], W, Wb);
              rowMajor(out[0], n, nb) = Wb;
            })[0];
          },
          py::arg("q"), py::arg("dq"), py::arg("ddq"))
      .def(
          "energy_regressor",
          [](PyBase& b, const Array& q, const Array& dq) {
            PyModel& s = *b.model;
            const long n = s.model.nq();
            SampleBatch batch({{&q, "q"}, {&dq, "dq"}}, n);
            const long nb = b.bp.eom.size();
            const long P = b.bp.layout.size(static_cast<int>(n));
            Data data(s.model);
            Eigen::VectorXd wK(P), wP(P);
            return perSample<1>(batch, {{{nb}}}, [&](const auto& x, auto out) {
              baseEnergyRegressor(s.model, data, b.bp, x[0], x[1], wK, wP, vectorAt(out[0], nb));
            })[0];
          },
          py::arg("q"), py::arg("dq"))
      .def(
          "momentum_regressors",
          [](PyBase& b, const Array& q, const Array& dq) {
            PyModel& s = *b.model;
            const long n = s.model.nq();
            SampleBatch batch({{&q, "q"}, {&dq, "dq"}}, n);
            const long nb = b.bp.eom.size(), P = b.bp.layout.size(static_cast<int>(n));
            Data data(s.model);
            Eigen::MatrixXd W(n, P), Wl(n, P), Wpb(n, nb), Wlb(n, nb);
            auto [wp, wl] = perSample<2>(batch, {{{n, nb}, {n, nb}}}, [&](const auto& x, auto out) {
              baseMomentumRegressors(s.model, data, b.bp, x[0], x[1], W, Wl, Wpb, Wlb);
              rowMajor(out[0], n, nb) = Wpb;
              rowMajor(out[1], n, nb) = Wlb;
            });
            return py::make_tuple(wp, wl);
          },
          py::arg("q"), py::arg("dq"));

  m.def(
      "base_parameters",
      [](const std::shared_ptr<PyModel>& model, bool rotor, bool friction,
         const std::string& method, const std::vector<int>& order, double tolerance, int samples,
         unsigned seed, double snap, bool offset) {
        auto out = std::make_shared<PyBase>();
        if (snap > 0) {
          Model copy = model->model;
          out->snapped = snapRightAngles(copy, snap);
          out->model = std::make_shared<PyModel>(std::move(copy));
        } else {
          out->model = model;
        }
        BaseOptions o;
        o.layout = out->model->model.layout(rotor, friction, offset);
        o.order = order;
        o.tolerance = tolerance;
        o.samples = samples;
        o.seed = seed;
        if (method == "projection")
          o.method = BaseMethod::Projection;
        else if (method == "numerical")
          o.method = BaseMethod::Numerical;
        else if (method == "recursive")
          o.method = BaseMethod::Recursive;
        else
          throw ArgumentError("method must be 'projection', 'recursive' or 'numerical', got '" +
                              method + "'");
        {
          py::gil_scoped_release release;
          out->bp = computeBaseParameters(out->model->model, o);
        }
        return out;
      },
      py::arg("model"), py::arg("rotor") = false, py::arg("friction") = false,
      py::arg("method") = "projection", py::arg("order") = std::vector<int>(),
      py::arg("tolerance") = kDefaultRankTolerance, py::arg("samples") = 0, py::arg("seed") = 1u,
      py::arg("snap") = 0.0, py::arg("offset") = false);
  m.def(
      "snap_changes",
      [](const std::shared_ptr<PyModel>& model, double tolerance) {
        Model copy = model->model;
        std::vector<SnapChange> changes;
        const std::vector<std::string> lines = snapRightAngles(copy, tolerance, &changes);
        py::list entries;
        for (const SnapChange& c : changes) {
          py::dict d;
          d["joint"] = c.joint;
          d["joint_name"] = c.joint_name;
          d["frame"] = c.frame;
          d["component"] = c.component;
          d["value"] = c.value;
          d["snapped"] = c.snapped;
          d["deviation"] = c.deviation;
          entries.append(d);
        }
        return py::make_tuple(entries, lines);
      },
      py::arg("model"), py::arg("tolerance") = 1e-3,
      "What a snap of `tolerance` [rad] would round in the model (which is unchanged): each "
      "angle and axis component rounded (dicts: joint, joint_name, frame 'origin' | 'link "
      "frame' | 'axis', component 'yaw' | 'pitch' | 'roll' | 'x' | 'y' | 'z', value, snapped, "
      "deviation) and the lines of text that describe the changes.");
  m.def(
      "influence_coordinates",
      [](const std::shared_ptr<PyModel>& model, bool rotor) {
        const InfluenceCoordinates ic = influenceCoordinates(model->model, {rotor, false});
        std::vector<std::string> basis;
        for (int r = 0; r < ic.rows(); ++r) basis.push_back(ic.basis(r).toString(model->model));
        return py::make_tuple(ic.dense(), basis);
      },
      py::arg("model"), py::arg("rotor") = false,
      "Z (rows x 10n or 11n) and the basis function of each row, as text.");
  m.def(
      "projection_cost",
      [](const std::shared_ptr<PyModel>& model, bool rotor) {
        const ProjectionCost c = projectionCost(model->model, {rotor, false});
        py::dict d;
        d["terms"] = c.terms;
        d["rows"] = c.rows;
        d["entries"] = c.entries;
        d["largest_stage"] = c.largest_stage;
        d["bytes"] = c.bytes;
        d["budget"] = kProjectionBudget;
        return d;
      },
      py::arg("model"), py::arg("rotor") = false,
      "Upper bounds of what the projection method forms (terms, rows, entries) and its memory "
      "estimate in bytes, counted on sparsity patterns before computing; `budget`: the limit.");
  m.def(
      "projection_limits",
      [] {
        const ProjectionLimits l = projectionLimits();
        py::dict d;
        d["chain_joints"] = l.chain_joints;
        d["tree_joints"] = l.tree_joints;
        d["root_path_joints"] = l.root_path_joints;
        d["parameters"] = l.parameters;
        d["budget_bytes"] = kProjectionBudget;
        return d;
      },
      "The projection method's limits, as projection_refusal checks them: most joints on a "
      "chain, on a tree and on one root path of a tree, most parameters, the memory budget in "
      "bytes.");
  m.def(
      "projection_refusal",
      [](const std::shared_ptr<PyModel>& model, bool rotor, bool friction) -> py::object {
        const std::string why =
            projectionRefusal(model->model, model->model.layout(rotor, friction));
        if (why.empty()) return py::none();
        return py::str(why);
      },
      py::arg("model"), py::arg("rotor") = false, py::arg("friction") = false,
      "Why the projection method cannot take the model with these joint terms (its joint, "
      "parameter and memory limits, checked before computing), or None when it can.");
  m.def(
      "recursive_refusal",
      [](const std::shared_ptr<PyModel>& model, bool rotor, bool friction) -> py::object {
        const std::string why =
            recursiveRefusal(model->model, {rotor, friction}, kDefaultRankTolerance);
        if (why.empty()) return py::none();
        return py::str(why);
      },
      py::arg("model"), py::arg("rotor") = false, py::arg("friction") = false,
      "Why the recursive method cannot take the model with these joint terms (rotor inertia of "
      "a motor coupling joints whose coupled energy it cannot prove independent of the links'), "
      "or None when it can.");
  m.def(
      "sole_joints",
      [](const Eigen::MatrixXd& T) {
        std::vector<int> out(static_cast<size_t>(T.rows()));
        for (Eigen::Index k = 0; k < T.rows(); ++k) out[k] = soleJoint(T, static_cast<int>(k));
        return out;
      },
      py::arg("T"),
      "Per motor (row of the transmission T), the joint it alone drives and drives alone, or -1 "
      "(it turns with several joints, or another motor turns that joint too): the motors whose "
      "rotor inertia and friction a joint can carry.");
  m.def("khalil_order", [](int n, bool rotor, bool friction) {
    return khalilOrder(n, {rotor, friction});
  });

  m.def("load_yaml",
        [](const std::string& path) { return std::make_shared<PyModel>(loadYaml(path)); });
  m.def(
      "parse_yaml",
      [](const std::string& text, const std::string& source) {
        return std::make_shared<PyModel>(parseYaml(text, source));
      },
      py::arg("text"), py::arg("source") = "<string>");
  m.def(
      "load_urdf",
      [](const std::string& path, const std::string& tip, const std::string& root_joint) {
        return std::make_shared<PyModel>(loadUrdf(path, tip, root_joint));
      },
      py::arg("path"), py::arg("tip") = "", py::arg("root_joint") = "");
  m.def(
      "parse_urdf",
      [](const std::string& xml, const std::string& tip, const std::string& source) {
        return std::make_shared<PyModel>(parseUrdf(xml, tip, source));
      },
      py::arg("xml"), py::arg("tip") = "", py::arg("source") = "<string>");
  m.def(
      "planar_arm",
      [](int n, bool vertical, double length, double mass) {
        return std::make_shared<PyModel>(planarArm(n, vertical, length, mass));
      },
      py::arg("n"), py::arg("vertical") = true, py::arg("length") = 0.5, py::arg("mass") = 2.0);
  m.def(
      "inertial_from_com",
      [](double mass, const Eigen::Vector3d& com, const Eigen::Matrix3d& I) {
        return Eigen::VectorXd(inertialFromCom(mass, com, I));
      },
      py::arg("mass"), py::arg("com"), py::arg("inertia"));
  m.def(
      "inertial_from_urdf",
      [](double mass, const Eigen::Vector3d& com, const Eigen::Matrix3d& R,
         const Eigen::Matrix3d& I) { return Eigen::VectorXd(inertialFromUrdf(mass, com, R, I)); },
      py::arg("mass"), py::arg("com"), py::arg("rotation"), py::arg("inertia"));
  m.def(
      "pose_error",
      [](const Eigen::Matrix4d& T, const Eigen::Matrix4d& target) {
        Vector6d e;
        poseError(isometry(T), isometry(target), e);
        return Eigen::VectorXd(e);
      },
      py::arg("T"), py::arg("target"),
      "The twist (p_target - p, rotation vector of R_target R^T) taking T onto target (the pose "
      "error of the inverse kinematics).");
  m.def("to_pinocchio_order", [](const Eigen::VectorXd& v) { return toPinocchioOrder(v); });
  m.def("from_pinocchio_order", [](const Eigen::VectorXd& v) { return fromPinocchioOrder(v); });
  bindControl(m);
  bindObserver(m);
  bindCodegen(m);
  bindCsv(m);
  bindMultibody(m);
  bindFilter(m);
}
