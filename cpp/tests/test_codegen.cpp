// The expression graph's simplifications, the generated Newton-Euler graphs against a closed form
// and against the classical recursion, the runtime base-parameter tapes, and their allocation
// freedom (malloc counter of this test program).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "codegen/internal.hpp"
#include "malloc_counter.hpp"
#include "mindyn/base_dynamics.hpp"
#include "mindyn/codegen/controller.hpp"
#include "mindyn/codegen/emit_c.hpp"
#include "mindyn/codegen/emit_st.hpp"
#include "mindyn/codegen/newton_euler.hpp"
#include "mindyn/multibody.hpp"
#include "mindyn/sincos.hpp"
#include "mindyn/slotine_li.hpp"
#include "mindyn/urdf.hpp"
#include "test_util.hpp"
#include "tree_paths.hpp"

using namespace mindyn;
using mindyn::test::Count;
using namespace mindyn::codegen;
using mindyn::test::random;
using mindyn::test::relErr;
using mindyn::test::withExtras;

namespace {

Eigen::VectorXd outputs(const GeneratedFunction& f, const Eigen::VectorXd& q,
                        const Eigen::VectorXd& dq, const Eigen::VectorXd& ddq,
                        const Eigen::VectorXd& p) {
  const auto v = f.graph.evaluate({q.data(), dq.data(), ddq.data(), p.data()});
  Eigen::VectorXd out(f.outputs.size());
  for (size_t i = 0; i < f.outputs.size(); ++i) out[i] = f.graph.value(v, f.outputs[i]);
  return out;
}

// The Slotine-Li products of the controller step in each of their forms against a regressor Y of
// the parameter set (n x np): Y p, Y^T s and |Y|^2.
void expectSlotineLiProducts(const Model& model, const ParameterSet& ps, const Eigen::MatrixXd& Y,
                             const Eigen::VectorXd& q, const Eigen::VectorXd& dq,
                             const Eigen::VectorXd& dqr, const Eigen::VectorXd& ddqr,
                             const Eigen::VectorXd& s, const Eigen::VectorXd& p, double tol) {
  const long n = model.nq(), np = ps.size();
  for (SlotineLiForm form : {SlotineLiForm::Columns, SlotineLiForm::PassColumns,
                             SlotineLiForm::ColumnsAdjoint, SlotineLiForm::PassAdjoint}) {
    const GeneratedFunction f = internal::generateSlotineLiForm(model, ps, true, form);
    InputValues in{q.data(), dq.data(), nullptr, p.data()};
    in.dqr = dqr.data();
    in.ddqr = ddqr.data();
    in.s = s.data();
    const auto v = f.graph.evaluate(in);
    Eigen::VectorXd out(f.outputs.size());
    for (size_t i = 0; i < f.outputs.size(); ++i) out[i] = f.graph.value(v, f.outputs[i]);
    ASSERT_EQ(out.size(), n + np + 1);
    EXPECT_LT(relErr(out.head(n), Y * p), tol) << model.name << " " << toString(form);
    EXPECT_LT(relErr(out.segment(n, np), Y.transpose() * s), tol) << model.name;
    EXPECT_LT(std::abs(out[n + np] - Y.squaredNorm()) / Y.squaredNorm(), tol) << model.name;
  }
}

// The three tapes of `bd` run once each; returns the number of allocations they made.
long runTapes(BaseDynamics& bd, const Eigen::VectorXd& q, const Eigen::VectorXd& dq,
              const Eigen::VectorXd& ddq, const Eigen::VectorXd& p, Eigen::VectorXd& tau,
              Eigen::VectorXd& gravity, Eigen::MatrixXd& W) {
  Count c;
  bd.inverseDynamics(q, dq, ddq, p, tau);
  bd.gravity(q, p, gravity);
  bd.regressor(q, dq, ddq, W);
  return c.value();
}

}  // namespace

TEST(Expr, FoldingAndSharing) {
  Graph g;
  const Ref x = g.input(InputKind::DQ, 0), y = g.input(InputKind::DDQ, 1);
  EXPECT_EQ(g.mul(x, Graph::one()), x);
  EXPECT_EQ(g.mul(g.constant(-1.0), x), -x);
  EXPECT_EQ(g.mul(x, Graph::zero()), Graph::zero());
  EXPECT_EQ(g.add(x, Graph::zero()), x);
  EXPECT_EQ(g.sub(x, x), Graph::zero());
  EXPECT_EQ(g.mul(x, y), g.mul(y, x));
  EXPECT_EQ(g.mul(-x, y), -g.mul(x, y));
  EXPECT_EQ(g.sub(x, y), -g.sub(y, x));
  EXPECT_EQ(g.add(x, y), g.add(y, x));
  EXPECT_EQ(g.constantValue(g.add(g.constant(2.0), g.constant(-0.5))), 1.5);
  EXPECT_EQ(g.constantValue(g.mul(g.constant(3.0), g.constant(-2.0))), -6.0);
  // constants gather: 2 * (3 * x) is one multiplication 6 * x
  EXPECT_EQ(g.mul(g.constant(2.0), g.mul(g.constant(3.0), x)), g.mul(g.constant(6.0), x));
  // x + x is 2 x, and so gathers too: 3 x + 3 x = 6 x
  EXPECT_EQ(g.add(x, x), g.mul(g.constant(2.0), x));
  EXPECT_EQ(g.add(g.mul(g.constant(3.0), x), g.mul(g.constant(3.0), x)), g.mul(g.constant(6.0), x));
  EXPECT_EQ(g.sub(-x, x), g.mul(g.constant(-2.0), x));
  EXPECT_EQ(g.cos(-x), g.cos(x));
  EXPECT_EQ(g.sin(-x), -g.sin(x));
  // x*y + y*x - 2*(x*y): built three ways, scheduled once
  const Ref xy = g.mul(x, y);
  const Ref e = g.sub(g.add(g.mul(x, y), g.mul(y, x)), g.add(xy, xy));
  EXPECT_EQ(e, Graph::zero());
  const Program p = schedule(g, {g.add(g.mul(x, y), g.mul(y, x)), -g.mul(y, x)});
  EXPECT_EQ(p.count.mul, 2);  // x y and 2 (x y)
  EXPECT_EQ(p.count.add, 0);
  EXPECT_EQ(p.count.neg, 1);
  const double xv = 0.3, yv = -1.7;
  const double dqv[1] = {xv}, ddqv[2] = {0.0, yv};
  const auto v = g.evaluate({nullptr, dqv, ddqv, nullptr});
  EXPECT_DOUBLE_EQ(g.value(v, p.outputs[0]), 2 * xv * yv);
  EXPECT_DOUBLE_EQ(g.value(v, p.outputs[1]), -xv * yv);
  // a term cancelled against one of an operand's terms leaves the other term
  const Ref z = g.input(InputKind::Q, 2);
  const Ref xz = g.add(x, z);
  EXPECT_EQ(g.sub(xz, x), z);
  EXPECT_EQ(g.sub(z, xz), -x);
  EXPECT_EQ(g.add(-xz, x), -z);
  EXPECT_EQ(g.add(g.sub(xy, z), z), xy);
}

TEST(Codegen, TwoLinkPlanarClosedForm) {
  // Vertical-plane two-link arm of uniform rods (planarArm): the textbook closed form.
  const double l = 0.5, m = 2.0, r = 0.02, g = 9.81;
  const Model model = planarArm(2, true, l, m);
  const BaseParameters bp = computeBaseParameters(model);
  const ParameterSet ps = baseParameterSet(model, bp);
  const auto id = generate(model, ps, Function::InverseDynamics);
  const auto idn = generate(model, ps, Function::InverseDynamics, true);
  const auto grav = generate(model, ps, Function::Gravity);
  std::mt19937 rng(1);
  for (int trial = 0; trial < 10; ++trial) {
    const Eigen::VectorXd q = random(rng, 2, M_PI), dq = random(rng, 2, 2), ddq = random(rng, 2, 3);
    Eigen::Vector2d gexp;
    const Eigen::Vector2d expected = test::twoLinkTorque(q, dq, ddq, l, m, r, g, &gexp);
    EXPECT_LT(relErr(outputs(id, q, dq, ddq, ps.values), expected), 1e-12);
    EXPECT_LT(relErr(outputs(idn, q, dq, ddq, Eigen::VectorXd()), expected), 1e-12);
    EXPECT_LT(relErr(outputs(grav, q, dq, ddq, ps.values), gexp), 1e-12);
  }
}

TEST(Codegen, BaseAndClassicalGraphsMatchTheClassicalRecursion) {
  std::mt19937 rng(3);
  for (const char* name : {"puma560", "zcr07s", "stanford", "puma560_3"}) {
    const Model model = withExtras(loadYaml(test::robotFile(name)), rng);
    Data data(model);
    const int n = model.nq();
    for (ParameterLayout layout : {ParameterLayout{false, false}, ParameterLayout{true, true}}) {
      BaseOptions opt;
      opt.layout = layout;
      const BaseParameters bp = computeBaseParameters(model, opt);
      const ParameterSet base = baseParameterSet(model, bp);
      const ParameterSet classical = classicalParameterSet(model, layout);
      const auto id = generate(model, base, Function::InverseDynamics);
      const auto grav = generate(model, base, Function::Gravity);
      const auto reg = generate(model, base, Function::Regressor);
      const auto cid = generate(model, classical, Function::InverseDynamics);
      // the base recursion exploits the zeros: fewer operations than the classical one
      EXPECT_LT(id.program.count.mul, cid.program.count.mul) << name;
      EXPECT_LT(id.program.count.add, cid.program.count.add) << name;
      for (int trial = 0; trial < 3; ++trial) {
        const Eigen::VectorXd q = random(rng, n, 3), dq = random(rng, n, 2),
                              ddq = random(rng, n, 2);
        const Eigen::VectorXd pi = random(rng, layout.size(n));
        const Eigen::VectorXd pb = bp.values(pi);
        Eigen::VectorXd tau(n), tg(n);
        Eigen::MatrixXd W(n, layout.size(n)), Wb(n, bp.eom.size());
        inverseDynamics(model, data, q, dq, ddq, pi, layout, tau);
        gravityTorque(model, data, q, pi, layout, tg);
        baseRegressor(model, data, bp, q, dq, ddq, W, Wb);
        EXPECT_LT(relErr(outputs(id, q, dq, ddq, pb), tau), 1e-12) << name;
        EXPECT_LT(relErr(outputs(cid, q, dq, ddq, pi), tau), 1e-12) << name;
        EXPECT_LT(relErr(outputs(grav, q, dq, ddq, pb), tg), 1e-12) << name;
        const Eigen::VectorXd w = outputs(reg, q, dq, ddq, pb);
        const Eigen::MatrixXd Wg = Eigen::Map<const Eigen::MatrixXd>(w.data(), bp.eom.size(), n);
        EXPECT_LT((Wg.transpose() - Wb).norm() / std::max(1.0, Wb.norm()), 1e-12) << name;
      }
    }
  }
}

// The Slotine-Li products of the controller step, in each of their forms, against the runtime
// Slotine-Li base regressor Y_b: Y_b p, Y_b^T s and |Y_b|^2, with and without torque offsets
// (a unit column per joint).
TEST(Codegen, SlotineLiProductsMatchTheRuntimeRegressor) {
  std::mt19937 rng(5);
  BaseOptions withJointTerms;
  withJointTerms.layout = {true, true};
  for (const char* name : {"zcr07s", "stanford", "puma560_3"}) {
    const Model model = withExtras(loadYaml(test::robotFile(name)), rng);
    const BaseParameters bp = computeBaseParameters(model, withJointTerms);
    Data data(model);
    SlotineLiData sl(model, bp.layout);
    const int n = model.nq();
    for (bool offsets : {false, true}) {
      ParameterSet ps = baseParameterSet(model, bp);
      if (offsets) ps = withOffsets(model, ps);
      const int np = ps.size(), nb = bp.eom.size();
      const Eigen::VectorXd q = random(rng, n, 3), dq = random(rng, n, 2), dqr = random(rng, n, 2),
                            ddqr = random(rng, n, 2), s = random(rng, n), p = random(rng, np);
      Eigen::MatrixXd Yb(n, nb), Y = Eigen::MatrixXd::Zero(n, np);
      slotineLiBaseRegressor(model, data, sl, bp, q, dq, dqr, ddqr, Yb);
      Y.leftCols(nb) = Yb;
      if (offsets) Y.rightCols(n).setIdentity();
      expectSlotineLiProducts(model, ps, Y, q, dq, dqr, ddqr, s, p, 1e-12);
    }
  }
}

// Every way of forming the link wrenches that the choice in generate() may take, forced on every
// link at once: own frame, or the joint frame before the motion with the inertia turned entry by
// entry, keeping its trace or split, each with the moment of the first moment taken before or
// after the motion. Standard DH (link frames off the joint axes), modified DH, a prismatic joint
// and joint axes that are not coordinate axes.
TEST(Codegen, EveryLinkFormMatchesTheClassicalRecursion) {
  std::mt19937 rng(11);
  const std::string skewed = R"(<robot name="skew"><link name="b"/>
    <link name="l1"><inertial><origin xyz="0.1 -0.05 0.2" rpy="0.3 0.2 0.1"/><mass value="2"/>
      <inertia ixx="0.05" ixy="0.01" ixz="-0.004" iyy="0.04" iyz="0.003" izz="0.03"/></inertial></link>
    <link name="l2"><inertial><origin xyz="-0.2 0.1 0.05" rpy="0 0.4 0"/><mass value="1.5"/>
      <inertia ixx="0.02" ixy="0.002" ixz="0.001" iyy="0.03" iyz="-0.002" izz="0.025"/></inertial></link>
    <link name="l3"><inertial><origin xyz="0.05 0.05 0.1" rpy="0 0 0"/><mass value="1"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.012" iyz="0" izz="0.008"/></inertial></link>
    <joint name="j1" type="revolute"><parent link="b"/><child link="l1"/><origin xyz="0 0 0.3" rpy="0.2 -0.1 0.3"/>
      <axis xyz="0.267 0.535 0.802"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
    <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0.3 0.1 0" rpy="1.0 0 0.5"/>
      <axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
    <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/><origin xyz="0.2 0 0.1" rpy="0 0 0"/>
      <axis xyz="-1 0 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  </robot>)";
  std::vector<std::pair<std::string, Model>> models;
  for (const char* name : {"puma560", "zcr07s", "stanford"})
    models.emplace_back(name, withExtras(loadYaml(test::robotFile(name)), rng));
  models.emplace_back("skewed", withExtras(parseUrdf(skewed), rng));
  for (const auto& [name, model] : models) {
    Data data(model);
    const int n = model.nq();
    const ParameterLayout layout{true, true};
    BaseOptions opt;
    opt.layout = layout;
    const BaseParameters bp = computeBaseParameters(model, opt);
    const ParameterSet base = baseParameterSet(model, bp);
    for (int form = 0; form < 8; ++form) {
      if (form == 4) continue;  // the same as 0
      const auto id = internal::generateWithLinkForm(model, base, Function::InverseDynamics, form);
      const auto reg = internal::generateWithLinkForm(model, base, Function::Regressor, form);
      for (int trial = 0; trial < 2; ++trial) {
        const Eigen::VectorXd q = random(rng, n, 3), dq = random(rng, n, 2),
                              ddq = random(rng, n, 2);
        const Eigen::VectorXd pi = random(rng, layout.size(n));
        const Eigen::VectorXd pb = bp.values(pi);
        Eigen::VectorXd tau(n);
        Eigen::MatrixXd W(n, layout.size(n)), Wb(n, bp.eom.size());
        inverseDynamics(model, data, q, dq, ddq, pi, layout, tau);
        baseRegressor(model, data, bp, q, dq, ddq, W, Wb);
        EXPECT_LT(relErr(outputs(id, q, dq, ddq, pb), tau), 1e-12) << name << " form " << form;
        const Eigen::VectorXd w = outputs(reg, q, dq, ddq, pb);
        const Eigen::MatrixXd Wg = Eigen::Map<const Eigen::MatrixXd>(w.data(), bp.eom.size(), n);
        EXPECT_LT((Wg.transpose() - Wb).norm() / std::max(1.0, Wb.norm()), 1e-12)
            << name << " form " << form;
      }
    }
  }
}

// Geometric constants within kGeometrySnap of 0 or +-1 are taken as exact and reported; what is
// derived from them (the rotation about a general axis) keeps products below that tolerance:
// an axis 3e-5 off z has u_x u_y = 9e-10, which still turns the link.
TEST(Codegen, GeometrySnapIsReportedAndLeavesDerivedConstantsAlone) {
  std::mt19937 rng(13);
  const auto arm = [](const std::string& rpy, const std::string& axis) {
    return R"(<robot name="snap"><link name="b"/>
    <link name="l1"><inertial><origin xyz="0.1 -0.05 0.2" rpy="0 0 0"/><mass value="2"/>
      <inertia ixx="0.05" ixy="0.01" ixz="-0.004" iyy="0.04" iyz="0.003" izz="0.03"/></inertial></link>
    <link name="l2"><inertial><origin xyz="-0.2 0.1 0.05" rpy="0 0 0"/><mass value="1.5"/>
      <inertia ixx="0.02" ixy="0.002" ixz="0.001" iyy="0.03" iyz="-0.002" izz="0.025"/></inertial></link>
    <joint name="j1" type="revolute"><parent link="b"/><child link="l1"/><origin xyz="0 0 0.3" rpy="0.4 0 0"/>
      <axis xyz=")" +
           axis + R"("/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
    <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0.3 0 0" rpy=")" +
           rpy +
           R"("/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
    </robot>)";
  };
  for (const bool truncated : {false, true}) {
    const Model model = parseUrdf(arm(truncated ? "0 1.57079632679 0" : "0 0.7 0",
                                      truncated ? "0 0 1" : "0.00003 0.00003 1"));
    Data data(model);
    const int n = model.nq();
    const ParameterLayout layout{false, false};
    const BaseParameters bp = computeBaseParameters(model, {});
    const auto id = generate(model, baseParameterSet(model, bp), Function::InverseDynamics);
    // two rotation entries, and residues of the translation moved along the axis, if it is
    if (truncated)
      EXPECT_GE(id.snap.count, 2);
    else
      EXPECT_EQ(id.snap.count, 0);
    EXPECT_NEAR(id.snap.largest, truncated ? std::abs(std::cos(1.57079632679)) : 0.0, 1e-16);
    for (int trial = 0; trial < 3; ++trial) {
      const Eigen::VectorXd q = random(rng, n, 3), dq = random(rng, n, 2), ddq = random(rng, n, 2);
      const Eigen::VectorXd pi = random(rng, layout.size(n));
      Eigen::VectorXd tau(n);
      inverseDynamics(model, data, q, dq, ddq, pi, layout, tau);
      // the 4.9e-12 taken as 0 moves the result by about that much; nothing else does
      EXPECT_LT(relErr(outputs(id, q, dq, ddq, bp.values(pi)), tau), truncated ? 1e-10 : 1e-13);
    }
  }
}

// The objective: additions first gives no more additions than the default, which gives no more
// operations in all; both stay exact (checked above and in the Python tests against Pinocchio).
TEST(Codegen, ObjectiveOrdersTheCounts) {
  for (const char* name : {"puma560", "zcr07s"}) {
    const Model model = loadYaml(test::robotFile(name));
    const ParameterSet base = baseParameterSet(model, computeBaseParameters(model));
    const OpCount ops = generate(model, base, Function::InverseDynamics).program.count;
    const OpCount adds =
        generate(model, base, Function::InverseDynamics, false, {}, Objective::Additions)
            .program.count;
    EXPECT_LE(adds.add, ops.add) << name;
    EXPECT_LE(ops.mul + ops.add, adds.mul + adds.add) << name;
  }
}

TEST(Codegen, NumericValuesAreBakedIn) {
  const Model model = loadYaml(test::robotFile("puma560"));
  const BaseParameters bp = computeBaseParameters(model);
  const ParameterSet ps = baseParameterSet(model, bp);
  const auto sym = generate(model, ps, Function::InverseDynamics);
  const auto num = generate(model, ps, Function::InverseDynamics, true);
  // zeros in the published values remove work
  EXPECT_LT(num.program.count.mul, sym.program.count.mul);
  for (int id = 0; id < num.graph.size(); ++id)
    EXPECT_FALSE(num.graph.node(id).op == Op::Input && num.graph.node(id).kind == InputKind::P &&
                 num.program.uses[id] > 0);
  std::mt19937 rng(4);
  const Eigen::VectorXd q = random(rng, 6), dq = random(rng, 6), ddq = random(rng, 6);
  EXPECT_LT(
      relErr(outputs(num, q, dq, ddq, Eigen::VectorXd()), outputs(sym, q, dq, ddq, ps.values)),
      1e-13);
  EXPECT_THROW(generate(model, ps, Function::InverseDynamics, true, Eigen::VectorXd::Ones(3)),
               ModelError);
}

TEST(Codegen, EmittersNameEverything) {
  const Model model = loadYaml(test::robotFile("puma560_3"));
  const BaseParameters bp = computeBaseParameters(model);
  const GeneratedCode code =
      generateCode(model, baseParameterSet(model, bp),
                   {Function::InverseDynamics, Function::Gravity, Function::Regressor}, "puma3");
  const CFiles c = emitC(code, "puma3.h");
  EXPECT_NE(c.header.find("void puma3_inverse_dynamics(const double q[3], const double dq[3], "
                          "const double ddq[3], const double p[15], double tau[3]);"),
            std::string::npos);
  EXPECT_NE(c.header.find("void puma3_gravity(const double q[3], const double p[15], "
                          "double tau[3]);"),
            std::string::npos);
  EXPECT_NE(c.header.find("double W[45]"), std::string::npos);
  for (const auto& name : bp.eom.names)
    EXPECT_NE(c.source.find("\"" + name + "\""), std::string::npos) << name;
  const std::string st = emitST(code);
  EXPECT_NE(st.find("FUNCTION_BLOCK puma3_inverse_dynamics"), std::string::npos);
  EXPECT_NE(st.find("W : ARRAY[1..3, 1..15] OF LREAL;"), std::string::npos);
  EXPECT_EQ(st.find("**"), std::string::npos);
  EXPECT_EQ(st.find("ATAN2"), std::string::npos);
  size_t longest = 0, start = 0;
  for (size_t i = 0; i <= st.size(); ++i)
    if (i == st.size() || st[i] == '\n') {
      longest = std::max(longest, i - start);
      start = i + 1;
    }
  EXPECT_LE(longest, 100u);
  EXPECT_THROW(generateCode(model, baseParameterSet(model, bp), {Function::Gravity}, "9lives"),
               ModelError);
  EXPECT_THROW(generateCode(model, baseParameterSet(model, bp), {Function::Gravity}, "a__b"),
               ModelError);
}

TEST(Codegen, StructuredTextBlocksAreTheProgram) {
  const Model model = loadYaml(test::robotFile("puma560_3"));
  const BaseParameters bp = computeBaseParameters(model);
  const int np = static_cast<int>(bp.eom.names.size());
  const GeneratedCode code =
      generateCode(model, baseParameterSet(model, bp),
                   {Function::InverseDynamics, Function::Gravity, Function::Regressor}, "puma3");
  const STProgram program = programST(code);
  EXPECT_EQ(writeST(program), emitST(code));
  ASSERT_EQ(program.blocks.size(), 3u);
  const auto names = [](const std::vector<STVariable>& vs) {
    std::string out;
    for (const auto& v : vs) out += v.name + " : " + declaredType(v) + "; ";
    return out;
  };
  const std::string P = "ARRAY[1.." + std::to_string(np) + "] OF LREAL; ";
  const std::string Q = "ARRAY[1..3] OF LREAL; ";
  const STFunctionBlock& id = program.blocks[0];
  EXPECT_EQ(id.name, "puma3_inverse_dynamics");
  EXPECT_EQ(names(id.inputs), "q : " + Q + "dq : " + Q + "ddq : " + Q + "p : " + P);
  EXPECT_EQ(names(id.outputs), "tau : " + Q);
  EXPECT_EQ(names(program.blocks[1].inputs), "q : " + Q + "p : " + P);
  const STFunctionBlock& reg = program.blocks[2];
  ASSERT_EQ(reg.outputs.size(), 1u);
  EXPECT_EQ(reg.outputs[0].dims, (std::vector<std::pair<int, int>>{{1, 3}, {1, np}}));
  for (const auto& b : program.blocks) {
    EXPECT_FALSE(b.locals.empty());
    for (size_t k = 0; k < b.locals.size(); ++k) {
      EXPECT_EQ(b.locals[k].name, "t" + std::to_string(k + 1));
      EXPECT_EQ(declaredType(b.locals[k]), "LREAL");
      // each temporary is assigned in the body
      EXPECT_NE(b.body.find(b.locals[k].name + " := "), std::string::npos);
    }
    EXPECT_NE(b.note.find(" mul, "), std::string::npos);
  }
}

TEST(BaseDynamics, TapesMatchTheClassicalRecursionAndAllocateNothing) {
  std::mt19937 rng(5);
  for (const char* name : {"puma560", "zcr07s", "stanford"}) {
    const Model model = withExtras(loadYaml(test::robotFile(name)), rng);
    Data data(model);
    const int n = model.nq();
    BaseOptions opt;
    opt.layout = {true, true};
    const BaseParameters bp = computeBaseParameters(model, opt);
    BaseDynamics bd(model, bp);
    ASSERT_EQ(bd.np(), bp.eom.size());
    EXPECT_LT(bd.count(Function::InverseDynamics).mul, bd.count(Function::Regressor).mul);
    const Eigen::VectorXd q = random(rng, n, 3), dq = random(rng, n, 2), ddq = random(rng, n, 2);
    const Eigen::VectorXd pi = random(rng, opt.layout.size(n));
    const Eigen::VectorXd pb = bp.values(pi);
    Eigen::VectorXd tau(n), tg(n), t1(n), t2(n);
    Eigen::MatrixXd W(n, opt.layout.size(n)), Wb(n, bd.np()), Wt(n, bd.np());
    inverseDynamics(model, data, q, dq, ddq, pi, opt.layout, tau);
    gravityTorque(model, data, q, pi, opt.layout, tg);
    baseRegressor(model, data, bp, q, dq, ddq, W, Wb);
    long seen;
    {
      Count c;
      for (int i = 0; i < 3; ++i) {
        bd.inverseDynamics(q, dq, ddq, pb, t1);
        bd.gravity(q, pb, t2);
        bd.regressor(q, dq, ddq, Wt);
      }
      seen = c.value();
    }
    EXPECT_EQ(seen, 0) << name;
    EXPECT_LT(relErr(t1, tau), 1e-12) << name;
    EXPECT_LT(relErr(t2, tg), 1e-12) << name;
    EXPECT_LT((Wt - Wb).norm() / std::max(1.0, Wb.norm()), 1e-12) << name;
  }
}

TEST(BaseDynamics, TorqueOffsetsAddToTheInverseDynamicsOnly) {
  std::mt19937 rng(6);
  const Model model = withExtras(loadYaml(test::robotFile("zcr07s")), rng);
  Data data(model);
  const int n = model.nq();
  BaseOptions opt;
  opt.layout = {true, true};
  const BaseParameters bp = computeBaseParameters(model, opt);
  const ParameterSet ps = withOffsets(model, baseParameterSet(model, bp));
  EXPECT_THROW(withOffsets(model, ps), ModelError);
  const int nb = bp.eom.size();
  ASSERT_EQ(ps.size(), nb + n);
  EXPECT_EQ(ps.names.back(), "Off" + std::to_string(n));
  BaseDynamics bd(model, ps);
  const Eigen::VectorXd q = random(rng, n, 3), dq = random(rng, n, 2), ddq = random(rng, n, 2);
  const Eigen::VectorXd pi = random(rng, opt.layout.size(n)), off = random(rng, n);
  Eigen::VectorXd p(nb + n);
  p << bp.values(pi), off;
  Eigen::VectorXd tau(n), tg(n), t1(n), t2(n);
  Eigen::MatrixXd W(n, opt.layout.size(n)), Wb(n, nb), Wt(n, nb + n);
  inverseDynamics(model, data, q, dq, ddq, pi, opt.layout, tau);
  gravityTorque(model, data, q, pi, opt.layout, tg);
  baseRegressor(model, data, bp, q, dq, ddq, W, Wb);
  EXPECT_EQ(runTapes(bd, q, dq, ddq, p, t1, t2, Wt), 0);
  EXPECT_LT(relErr(t1, tau + off), 1e-12);
  EXPECT_LT(relErr(t2, tg), 1e-12);
  EXPECT_LT((Wt.leftCols(nb) - Wb).norm() / std::max(1.0, Wb.norm()), 1e-12);
  EXPECT_EQ(Wt.rightCols(n), Eigen::MatrixXd::Identity(n, n));
}

TEST(SinCos, WithinOneRoundingOfTheCLibrary) {
  std::mt19937 rng(11);
  std::vector<double> xs{0.0,    -0.0, 4.9e-324, -4.9e-324, 2.2e-308,
                         1e-300, 1e-8, -1e-3,    1.0e6,     -1.0e6};
  for (double range : {M_PI, 50.0, 1.0e6}) {
    std::uniform_real_distribution<double> u(-range, range);
    for (int i = 0; i < 100000; ++i) xs.push_back(u(rng));
  }
  std::uniform_real_distribution<double> tiny(-1e-9, 1e-9);
  for (int k = -2000; k <= 2000; ++k) {
    xs.push_back(k * M_PI_2 + tiny(rng));          // quadrant boundaries
    xs.push_back((k + 0.5) * M_PI_2 + tiny(rng));  // where the chosen quadrant changes
  }
  for (double x : xs) {
    double s, c;
    sinCos(x, s, c);
    const double bound = std::abs(x) < 1e-3 ? 2.3e-16 * std::abs(std::sin(x)) : 2.3e-16;
    ASSERT_LE(std::abs(s - std::sin(x)), bound) << std::hexfloat << x;
    ASSERT_LE(std::abs(c - std::cos(x)), 2.3e-16) << std::hexfloat << x;
  }
  // beyond 1e6 rad, NaN and infinities: the C library's values, bit for bit
  const double inf = std::numeric_limits<double>::infinity();
  for (double x : {std::nextafter(1.0e6, 2.0e6), -1.0e7, 1e300, inf, -inf,
                   std::numeric_limits<double>::quiet_NaN()}) {
    double s, c;
    sinCos(x, s, c);
    const double rs = std::sin(x), rc = std::cos(x);
    EXPECT_EQ(std::memcmp(&s, &rs, sizeof s), 0) << x;
    EXPECT_EQ(std::memcmp(&c, &rc, sizeof c), 0) << x;
  }
}

// Every kind of tape instruction: lone sines and cosines and pairs, products, sums and
// differences, products fused into a sum from either side, signs, tanh, exp of a value and of
// its negative; against direct formulas.
TEST(BaseDynamics, TapeEvaluatesEveryInstructionKind) {
  GeneratedFunction f;
  Graph& g = f.graph;
  auto in = [&g](InputKind k, int i) { return Sym{&g, g.input(k, i)}; };
  const Sym q0 = in(InputKind::Q, 0), q1 = in(InputKind::Q, 1), q2 = in(InputKind::Q, 2);
  const Sym d0 = in(InputKind::DQ, 0), d1 = in(InputKind::DQ, 1), d2 = in(InputKind::DQ, 2);
  const Sym a0 = in(InputKind::DDQ, 0), a1 = in(InputKind::DDQ, 1), a2 = in(InputKind::DDQ, 2);
  const Sym p0 = in(InputKind::P, 0);
  const Sym s2{&g, g.sin(q2.r)}, c2{&g, g.cos(q2.r)};
  const std::vector<Sym> outs{{&g, g.sin(q0.r)},
                              {&g, g.cos(q1.r)},
                              s2 * c2 + p0,
                              d0 * d1,
                              d0 + d1,
                              d0 - d1,
                              d0 * a1 + a0,
                              d1 * a0 - a1,
                              a2 - d2 * a0,
                              -(d2 * d1),
                              2.5 * p0,
                              {&g, g.sign(d0.r)},
                              {&g, g.sign(d2.r)},
                              {&g, g.tanh(d0.r)},
                              {&g, g.tanh(-(d1 * a0).r)},
                              {&g, g.exp(-(d1 * d1).r)},
                              {&g, g.exp(a2.r)}};
  for (const Sym& o : outs) f.outputs.push_back(o.r);
  f.program = schedule(g, f.outputs);
  Tape tape(f);
  const double q[3] = {0.7, -2.9, 123.4}, dq[3] = {-1.3, 0.4, 0.0}, ddq[3] = {2.2, -0.6, 1.9};
  const double p[1] = {-0.35};
  const std::vector<double> expected{std::sin(q[0]),
                                     std::cos(q[1]),
                                     std::sin(q[2]) * std::cos(q[2]) + p[0],
                                     dq[0] * dq[1],
                                     dq[0] + dq[1],
                                     dq[0] - dq[1],
                                     dq[0] * ddq[1] + ddq[0],
                                     dq[1] * ddq[0] - ddq[1],
                                     ddq[2] - dq[2] * ddq[0],
                                     -(dq[2] * dq[1]),
                                     2.5 * p[0],
                                     -1.0,
                                     0.0,
                                     std::tanh(dq[0]),
                                     -std::tanh(dq[1] * ddq[0]),
                                     std::exp(-dq[1] * dq[1]),
                                     std::exp(ddq[2])};
  std::vector<double> out(expected.size());
  tape.run(q, dq, ddq, p, out.data());
  for (size_t i = 0; i < out.size(); ++i) EXPECT_NEAR(out[i], expected[i], 1e-15) << i;
  EXPECT_EQ(tape.count().trig, 4);
  EXPECT_EQ(tape.count().tanh, 2);
  EXPECT_EQ(tape.count().exp, 2);
}

TEST(BaseDynamics, TheCounterSeesAllocations) {
  long seen;
  {
    Count c;
    auto* v = new std::vector<double>(100);
    seen = c.value();
    delete v;
  }
  EXPECT_GE(seen, 1);
}

TEST(BaseDynamics, RejectsBaseParametersOfAnotherModel) {
  const Model a = loadYaml(test::robotFile("puma560")), b = loadYaml(test::robotFile("puma560_3"));
  EXPECT_THROW(BaseDynamics(b, computeBaseParameters(a)), ModelError);
}

namespace {

// The classical regressor of a tree from the serial chains of its paths, by the runtime recursion
// on chains alone (tree_paths.hpp).
Eigen::MatrixXd treeRegressor(const Model& tree, ParameterLayout layout, const Eigen::VectorXd& q,
                              const Eigen::VectorXd& dq, const Eigen::VectorXd& ddq) {
  return test::pathRegressor(tree, q, dq, ddq, layout);
}

// The random trees of the tree tests: sizes up to 10, generic or special geometry, revolute or
// mixed joints; every third one a chain, so that a chain and a tree of the same draw both occur.
std::vector<Model> randomTrees(std::mt19937& rng) {
  std::vector<Model> out;
  int i = 0;
  for (int n : {2, 3, 4, 6, 8, 10})
    for (bool special : {false, true}) {
      const bool prismatic = (i % 2) == 1;
      out.push_back(test::randomChain(rng, n, prismatic, special, /*tree=*/i % 3 != 2));
      ++i;
    }
  return out;
}

}  // namespace

// The generated inverse dynamics, gravity torque and regressor of random trees (classical
// parameters, with and without the joint terms; the cheapest formulation the search finds, and
// every link form forced on all links) against the trees' regressor built from the runtime
// recursion on the chains of their paths. Tolerance 1e-10: the sums of up to 10 links' terms of
// magnitude ~10 in double precision are exact to ~1e-14; the geometry's snapping of multiples of
// pi/2 moves values by ~1e-16.
TEST(CodegenTree, GeneratedRecursionMatchesTheChainsOfItsPaths) {
  std::mt19937 rng(21);
  for (const Model& model : randomTrees(rng)) {
    const int n = model.nq();
    for (ParameterLayout layout : {ParameterLayout{false, false}, ParameterLayout{true, true}}) {
      const ParameterSet ps = classicalParameterSet(model, layout);
      const int P = layout.size(n);
      const auto id = generate(model, ps, Function::InverseDynamics);
      const auto grav = generate(model, ps, Function::Gravity);
      const auto reg = generate(model, ps, Function::Regressor);
      std::vector<GeneratedFunction> forms;
      for (int form : {1, 2, 3, 5, 6, 7})
        forms.push_back(internal::generateWithLinkForm(model, ps, Function::InverseDynamics, form));
      const Eigen::VectorXd q = random(rng, n, 3), dq = random(rng, n, 2), ddq = random(rng, n, 2);
      const Eigen::VectorXd pi = random(rng, P), zero = Eigen::VectorXd::Zero(n);
      const Eigen::MatrixXd W = treeRegressor(model, layout, q, dq, ddq);
      const Eigen::MatrixXd Wg = treeRegressor(model, layout, q, zero, zero);
      const std::string what = model.name + (layout.rotor ? " rotor+friction" : "");
      EXPECT_LT(relErr(outputs(id, q, dq, ddq, pi), W * pi), 1e-10) << what;
      EXPECT_LT(relErr(outputs(grav, q, dq, ddq, pi), Wg * pi), 1e-10) << what;
      const Eigen::VectorXd w = outputs(reg, q, dq, ddq, pi);
      const Eigen::MatrixXd Wr = Eigen::Map<const Eigen::MatrixXd>(w.data(), P, n).transpose();
      EXPECT_LT((Wr - W).norm() / std::max(1.0, W.norm()), 1e-10) << what;
      for (const auto& f : forms)
        EXPECT_LT(relErr(outputs(f, q, dq, ddq, pi), W * pi), 1e-10) << what;
    }
  }
}

// A tree whose every link hangs from the base (a star) has no coupling at all: each joint's torque
// is that of a one-joint arm. A tree of two copies of one chain on a common first joint, the two
// branches moved alike, carries on that first joint twice the branch load of the chain. Closed
// checks that need no recursion on trees.
TEST(CodegenTree, StarAndTwinBranchesAgreeWithChains) {
  std::mt19937 rng(23);
  const Model arm = test::randomChain(rng, 4, true, false);
  const ParameterLayout layout{true, true};
  // star: the four joints of `arm`, each on the base
  Model star = arm;
  star.name = "star";
  star.parents = {-1, -1, -1, -1};
  // twins: joint 0, then joints 1..3 twice, both copies on joint 0
  Model twins = arm;
  twins.name = "twins";
  twins.parents = {-1, 0, 1, 2, 0, 4, 5};
  for (int k = 1; k < 4; ++k) {
    twins.joints.push_back(arm.joints[k]);
    twins.link_names.push_back(arm.link_names[k + 1] + "b");
  }
  auto twice = [](const Eigen::VectorXd& x, long tail) {
    Eigen::VectorXd y(x.size() + tail);
    y << x, x.tail(tail);
    return y;
  };
  twins.inertial = twice(arm.inertial, 30);
  twins.rotor_inertia = twice(arm.rotor_inertia, 3);
  twins.viscous = twice(arm.viscous, 3);
  twins.coulomb = twice(arm.coulomb, 3);
  const Eigen::VectorXd pa = arm.parameters(layout);
  const int per = layout.perLink();
  const Eigen::VectorXd pt = twice(pa, 3 * per);
  ASSERT_EQ(pt, twins.parameters(layout));
  const auto idStar =
      generate(star, classicalParameterSet(star, layout), Function::InverseDynamics);
  const auto idTwins =
      generate(twins, classicalParameterSet(twins, layout), Function::InverseDynamics);
  Data data(arm);
  for (int trial = 0; trial < 3; ++trial) {
    const Eigen::VectorXd q = random(rng, 4, 3), dq = random(rng, 4, 2), ddq = random(rng, 4, 2);
    Eigen::VectorXd expected(4);
    for (int k = 0; k < 4; ++k) {
      Model one;
      one.name = "one";
      one.convention = arm.convention;
      one.gravity = arm.gravity;
      one.joints = {arm.joints[k]};
      one.link_names = {"base", "l"};
      one.inertial = arm.inertial.segment(10 * k, 10);
      one.rotor_inertia = arm.rotor_inertia.segment(k, 1);
      one.viscous = arm.viscous.segment(k, 1);
      one.coulomb = arm.coulomb.segment(k, 1);
      Data d1(one);
      Eigen::VectorXd t(1);
      inverseDynamics(one, d1, q.segment(k, 1), dq.segment(k, 1), ddq.segment(k, 1),
                      pa.segment(k * per, per), layout, t);
      expected[k] = t[0];
    }
    EXPECT_LT(relErr(outputs(idStar, q, dq, ddq, pa), expected), 1e-10);
    // the chain with its links 2..4 of double mass, inertia, rotor and friction: the same
    // torque on joint 1 as the twins; on joints 2..4, the twins' branches each carry half
    Eigen::VectorXd pd = pa;
    pd.tail(3 * per) *= 2.0;
    Eigen::VectorXd tauArm(4), tauDouble(4);
    inverseDynamics(arm, data, q, dq, ddq, pa, layout, tauArm);
    inverseDynamics(arm, data, q, dq, ddq, pd, layout, tauDouble);
    Eigen::VectorXd qt(7), dqt(7), ddqt(7);
    qt << q, q.tail(3);
    dqt << dq, dq.tail(3);
    ddqt << ddq, ddq.tail(3);
    Eigen::VectorXd expectedTwins(7);
    expectedTwins << tauDouble[0], tauArm.tail(3), tauArm.tail(3);
    EXPECT_LT(relErr(outputs(idTwins, qt, dqt, ddqt, pt), expectedTwins), 1e-10);
  }
}

// The Slotine-Li products of the controller step on random trees, in each form, with and without
// torque offsets, against the classical Slotine-Li regressor built from the chains of the paths.
TEST(CodegenTree, SlotineLiProductsMatchTheChainsOfItsPaths) {
  std::mt19937 rng(25);
  const ParameterLayout layout{true, true};
  for (const Model& model : randomTrees(rng)) {
    const int n = model.nq();
    if (n > 6) continue;  // the column forms grow with n times the parameter count
    const Eigen::VectorXd q = random(rng, n, 3), dq = random(rng, n, 2), dqr = random(rng, n, 2),
                          ddqr = random(rng, n, 2), s = random(rng, n);
    const Eigen::MatrixXd Yc =
        test::assembleByPaths(model, layout, [&](const Model& c, const std::vector<int>& path) {
          Data data(c);
          SlotineLiData sl(c, layout);
          Eigen::MatrixXd Y(c.nq(), layout.size(c.nq()));
          slotineLiRegressor(c, data, sl, test::along(path, q), test::along(path, dq),
                             test::along(path, dqr), test::along(path, ddqr), layout, Y);
          return Y;
        });
    for (bool offsets : {false, true}) {
      ParameterSet ps = classicalParameterSet(model, layout);
      if (offsets) ps = withOffsets(model, ps);
      const int np = ps.size(), P = layout.size(n);
      const Eigen::VectorXd p = random(rng, np);
      Eigen::MatrixXd Y = Eigen::MatrixXd::Zero(n, np);
      Y.leftCols(P) = Yc;
      if (offsets) Y.rightCols(n).setIdentity();
      expectSlotineLiProducts(model, ps, Y, q, dq, dqr, ddqr, s, p, 1e-10);
    }
  }
}

// The runtime tapes on a tree (a parameter set of random combinations pi = E p, with torque
// offsets): inverse dynamics, gravity and regressor against the tree's regressor from its paths,
// and nothing allocated.
TEST(CodegenTree, TapesMatchTheChainsOfItsPathsAndAllocateNothing) {
  std::mt19937 rng(27);
  const ParameterLayout layout{true, true};
  for (const Model& model : randomTrees(rng)) {
    const int n = model.nq(), P = layout.size(n);
    if (n > 6) continue;
    ParameterSet ps = classicalParameterSet(model, layout);
    const int np = P / 2;
    ps.E = Eigen::MatrixXd::Zero(P, np);
    for (int c = 0; c < P; ++c) ps.E(c, c % np) = 1.0 + c % 3;
    ps.names.resize(static_cast<size_t>(np));
    ps.values = random(rng, np);
    ps = withOffsets(model, ps);
    BaseDynamics bd(model, ps);
    const Eigen::VectorXd q = random(rng, n, 3), dq = random(rng, n, 2), ddq = random(rng, n, 2);
    const Eigen::VectorXd p = random(rng, np + n);
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n);
    const Eigen::MatrixXd E = ps.E.leftCols(np);
    const Eigen::MatrixXd W = treeRegressor(model, layout, q, dq, ddq) * E;
    const Eigen::MatrixXd Wg = treeRegressor(model, layout, q, zero, zero) * E;
    Eigen::VectorXd t1(n), t2(n);
    Eigen::MatrixXd Wt(n, np + n);
    EXPECT_EQ(runTapes(bd, q, dq, ddq, p, t1, t2, Wt), 0) << model.name;
    EXPECT_LT(relErr(t1, W * p.head(np) + p.tail(n)), 1e-10) << model.name;
    EXPECT_LT(relErr(t2, Wg * p.head(np)), 1e-10) << model.name;
    EXPECT_LT((Wt.leftCols(np) - W).norm() / std::max(1.0, W.norm()), 1e-10) << model.name;
    EXPECT_EQ(Wt.rightCols(n), Eigen::MatrixXd::Identity(n, n)) << model.name;
  }
}

// The header of a tree's code lists its joints in the order of q with the joint each is mounted on;
// a chain's does not.
TEST(CodegenTree, HeaderListsTheJointsOfATree) {
  std::mt19937 rng(29);
  Model tree = test::randomChain(rng, 4, false, true, true);
  tree.parents = {-1, 0, -1, 0};
  const ParameterSet ps = classicalParameterSet(tree, {});
  const GeneratedCode code = generateCode(tree, ps, {Function::Gravity}, "tree");
  const std::string header = emitC(code, "tree.h").header, st = emitST(code);
  const std::string list =
      " *   1. j1 (on the base)\n *   2. j2 (on j1)\n *   3. j3 (on the base)\n *   4. j4 (on "
      "j1)\n";
  EXPECT_NE(header.find(list), std::string::npos) << header;
  EXPECT_NE(st.find("(*   2. j2 (on j1) *)\n(*   3. j3 (on the base) *)"), std::string::npos) << st;
  ControllerSettings s;
  s.kd = s.kp = Eigen::VectorXd::Ones(4);
  const ControllerCode c = generateController(tree, ps, Controller::GravityCompensation, s, "t");
  EXPECT_NE(emitControllerC(c, "t.h").header.find(list), std::string::npos);
  Model chain = tree;
  chain.parents.clear();
  const std::string serial =
      emitC(generateCode(chain, ps, {Function::Gravity}, "chain"), "chain.h").header;
  EXPECT_EQ(serial.find("A tree"), std::string::npos);
  EXPECT_EQ(serial.find("(on "), std::string::npos);
}

// Base parameters of trees (the numerical method, on the runtime regressor of trees): the
// generated inverse dynamics, gravity and base regressor, run by the tapes, against the runtime
// recursion on the tree, W pi = W_b p_b and the tree's regressor from its paths. Random trees with
// consistent and with arbitrary inertia, with and without rotor and friction. Tolerance 1e-10 as
// above; the base values p_b = Y pi add round-off of the echelon form (~1e-13 here).
TEST(CodegenTree, BaseParameterCodeMatchesTheRuntimeRecursion) {
  std::mt19937 rng(31);
  std::vector<Model> models{test::randomTree(rng, 5, true), test::randomTree(rng, 8, false),
                            test::randomChain(rng, 6, true, true, true),
                            test::randomChain(rng, 10, false, false, true)};
  for (const Model& model : models) {
    const int n = model.nq();
    Data data(model);
    for (ParameterLayout layout : {ParameterLayout{false, false}, ParameterLayout{true, true}}) {
      BaseOptions opt;
      opt.layout = layout;
      opt.method = BaseMethod::Numerical;
      const BaseParameters bp = computeBaseParameters(model, opt);
      const int P = layout.size(n), nb = bp.eom.size();
      BaseDynamics bd(model, bp);
      const Eigen::VectorXd q = random(rng, n, 3), dq = random(rng, n, 2), ddq = random(rng, n, 2);
      const Eigen::VectorXd pi = random(rng, P), pb = bp.values(pi);
      Eigen::VectorXd tau(n), tg(n), t1(n), t2(n);
      Eigen::MatrixXd W(n, P), Wb(n, nb), Wt(n, nb);
      inverseDynamics(model, data, q, dq, ddq, pi, layout, tau);
      gravityTorque(model, data, q, pi, layout, tg);
      regressor(model, data, q, dq, ddq, layout, W);
      const std::string what = model.name + (layout.rotor ? " rotor+friction" : "");
      // the runtime recursion on the tree and the chains of its paths agree
      ASSERT_LT((W - treeRegressor(model, layout, q, dq, ddq)).norm() / W.norm(), 1e-12) << what;
      EXPECT_EQ(runTapes(bd, q, dq, ddq, pb, t1, t2, Wt), 0) << what;
      EXPECT_LT(relErr(t1, tau), 1e-10) << what;
      EXPECT_LT(relErr(t1, W * pi), 1e-10) << what;
      EXPECT_LT(relErr(t2, tg), 1e-10) << what;
      EXPECT_LT(relErr(Wt * pb, W * pi), 1e-10) << what;
      baseRegressor(model, data, bp, q, dq, ddq, W, Wb);
      EXPECT_LT((Wt - Wb).norm() / std::max(1.0, Wb.norm()), 1e-10) << what;
    }
  }
}

namespace {

// A random tree (test::randomTree) under a free-flyer or planar joint with random constant
// transforms on the fixed base: the tree's joints on the base are mounted on the floating body.
Model floatingTree(std::mt19937& rng, JointType root) {
  Model tree = test::randomTree(rng, 6, false);
  Model m = tree;
  m.name = "floating";
  Joint j;
  j.name = "fly";
  j.type = root;
  j.pre.linear() = Eigen::AngleAxisd(0.4, test::randomUnit(rng)).toRotationMatrix();
  j.pre.translation() = random(rng, 3, 0.3);
  j.post.linear() = Eigen::AngleAxisd(-0.8, test::randomUnit(rng)).toRotationMatrix();
  j.post.translation() = random(rng, 3, 0.2);
  m.joints.insert(m.joints.begin(), j);
  m.link_names.insert(m.link_names.begin() + 1, "body");
  m.parents.assign(1, -1);
  for (int k = 0; k < tree.nq(); ++k) m.parents.push_back(tree.parent(k) + 1);
  m.inertial.resize(10 * m.nq());
  m.inertial << inertialFromCom(4.0, Eigen::Vector3d(0.1, -0.05, 0.02),
                                Eigen::Vector3d(0.2, 0.3, 0.25).asDiagonal()),
      tree.inertial;
  m.rotor_inertia = m.viscous = m.coulomb = Eigen::VectorXd::Zero(m.nq());
  m.validate();
  return m;
}

Eigen::VectorXd evaluated(const GeneratedFunction& f, const InputValues& in) {
  const auto v = f.graph.evaluate(in);
  Eigen::VectorXd out(f.outputs.size());
  for (size_t i = 0; i < f.outputs.size(); ++i) out[i] = f.graph.value(v, f.outputs[i]);
  return out;
}

}  // namespace

// The generated recursion of a floating base against the multibody algorithms (which agree with
// Pinocchio's): inverse dynamics, gravity and regressor; the contact terms by virtual work: the
// change of tau that the wrenches make, times any joint velocity w, is minus the wrenches' power
// on the links' velocities for w (the links' velocities from the multibody motion pass).
TEST(CodegenFloating, MatchesTheMultibodyDynamicsAndTheContactsPower) {
  std::mt19937 rng(20261126);
  for (JointType root : {JointType::FreeFlyer, JointType::Planar}) {
    const Model model = floatingTree(rng, root);
    const int nv = model.velocitySize(), n = model.nq();
    const ParameterSet ps = classicalParameterSet(model, {});
    MultibodyData data(model);
    Eigen::VectorXd q(model.configSize());
    randomConfiguration(model, rng, q);
    const Eigen::VectorXd dq = random(rng, nv), ddq = random(rng, nv), pi = model.inertial;
    Eigen::VectorXd ref(nv), g(nv);
    inverseDynamics(model, data, q, dq, ddq, pi, ref);
    inverseDynamics(model, data, q, Eigen::VectorXd::Zero(nv), Eigen::VectorXd::Zero(nv), pi, g);
    InputValues in{q.data(), dq.data(), ddq.data(), pi.data()};
    const auto id = generate(model, ps, Function::InverseDynamics);
    EXPECT_LT(relErr(evaluated(id, in), ref), 1e-12) << toString(root);
    EXPECT_LT(relErr(evaluated(generate(model, ps, Function::Gravity), in), g), 1e-12);
    const Eigen::VectorXd W = evaluated(generate(model, ps, Function::Regressor), in);
    EXPECT_LT(relErr(Eigen::Map<const Eigen::MatrixXd>(W.data(), 10 * n, nv).transpose() * pi, ref),
              1e-12);
    const std::vector<int> links = {2, n - 1, 0};
    const Eigen::VectorXd f = random(rng, 18, 5.0), w = random(rng, nv);
    Eigen::VectorXd ignored(nv);
    inverseDynamics(model, data, q, w, Eigen::VectorXd::Zero(nv), pi, ignored);  // data.v: J w
    for (bool world : {true, false}) {
      in.f = f.data();
      const auto withContacts = generate(model, ps, Function::InverseDynamics, false, {},
                                         Objective::Operations, Contacts{links, world});
      const Eigen::VectorXd change = evaluated(withContacts, in) - ref;
      double power = 0;
      for (size_t c = 0; c < links.size(); ++c) {
        const int k = links[c];
        const Eigen::Matrix3d R = world ? data.R0[k] : Eigen::Matrix3d::Identity();
        // force on the origin's velocity, moment on the angular velocity (link axes)
        power += (R.transpose() * f.segment<3>(6 * c)).dot(data.v[k].tail<3>()) +
                 (R.transpose() * f.segment<3>(6 * c + 3)).dot(data.v[k].head<3>());
      }
      EXPECT_NEAR(change.dot(w), -power, 1e-12 * f.norm() * w.norm() * 10) << world;
      EXPECT_GT(std::abs(power), 1e-3);
    }
  }
}

TEST(CodegenFloating, OtherMultiDofJointsAreRefusedNamingTheJoint) {
  const Model model = test::everyJointKind();
  try {
    classicalParameterSet(model, {});
    FAIL() << "a spherical joint was accepted";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("has the spherical joint 'ball'"), std::string::npos)
        << e.what();
  }
}
