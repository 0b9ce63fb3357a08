// Loading descriptions: errors that name the problem, parameter conversions checked against a
// direct mass-point integration, DH/MDH conventions, URDF chains.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>

#include "mindyn/urdf.hpp"
#include "test_util.hpp"

using namespace mindyn;

namespace {

template <class E, class F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  ADD_FAILURE() << "no exception";
  return "";
}

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

// Classical parameters of a box of point masses, summed directly in the link frame.
Eigen::Matrix<double, 10, 1> pointMassBox(const Eigen::Isometry3d& T, double a, double b, double c,
                                          double mass, int k = 12) {
  Eigen::Matrix<double, 10, 1> p = Eigen::Matrix<double, 10, 1>::Zero();
  const double dm = mass / (k * k * k);
  for (int i = 0; i < k; ++i)
    for (int j = 0; j < k; ++j)
      for (int l = 0; l < k; ++l) {
        const Eigen::Vector3d local(a * ((i + 0.5) / k - 0.5), b * ((j + 0.5) / k - 0.5),
                                    c * ((l + 0.5) / k - 0.5));
        const Eigen::Vector3d r = T * local;
        p[0] += dm * (r.y() * r.y() + r.z() * r.z());
        p[1] -= dm * r.x() * r.y();
        p[2] -= dm * r.x() * r.z();
        p[3] += dm * (r.x() * r.x() + r.z() * r.z());
        p[4] -= dm * r.y() * r.z();
        p[5] += dm * (r.x() * r.x() + r.y() * r.y());
        p.segment<3>(6) += dm * r;
        p[9] += dm;
      }
  return p;
}

}  // namespace

TEST(Parameters, UrdfInertialMatchesPointMassIntegration) {
  const double a = 0.3, b = 0.2, c = 0.1, m = 2.5;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() << 0.1, -0.2, 0.3;
  T.linear() = (Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(-0.7, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(1.1, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  // The same discretisation about its own centre, in its own axes: the URDF <inertia> values.
  const auto local = pointMassBox(Eigen::Isometry3d::Identity(), a, b, c, m);
  Eigen::Matrix3d Ic = inertiaTensor(local);
  const auto fromUrdf = inertialFromUrdf(m, T.translation(), T.linear(), Ic);
  const auto direct = pointMassBox(T, a, b, c, m);
  EXPECT_LT((fromUrdf - direct).norm(), 1e-12 * direct.norm()) << fromUrdf.transpose() << "\n"
                                                               << direct.transpose();
}

TEST(Parameters, TransformInertialMatchesPointMassIntegration) {
  Eigen::Isometry3d child = Eigen::Isometry3d::Identity();
  child.translation() << 0.05, 0.02, -0.04;
  child.linear() = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  Eigen::Isometry3d parent_T_child = Eigen::Isometry3d::Identity();
  parent_T_child.translation() << -0.3, 0.1, 0.2;
  parent_T_child.linear() =
      Eigen::AngleAxisd(-1.2, Eigen::Vector3d(0, 1, 1).normalized()).toRotationMatrix();
  const auto inChild = pointMassBox(child, 0.2, 0.1, 0.05, 1.5);
  const auto inParent = pointMassBox(parent_T_child * child, 0.2, 0.1, 0.05, 1.5);
  EXPECT_LT((transformInertial(inChild, parent_T_child) - inParent).norm(), 1e-12);
}

TEST(Parameters, PinocchioOrderRoundTripAndLayout) {
  Eigen::VectorXd p(20);
  for (int i = 0; i < 20; ++i) p[i] = i + 1;
  const Eigen::VectorXd pin = toPinocchioOrder(p);
  // m, mcx, mcy, mcz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz of link 1 = M MX MY MZ XX XY YY XZ YZ ZZ
  Eigen::VectorXd expect(10);
  expect << 10, 7, 8, 9, 1, 2, 4, 3, 5, 6;
  EXPECT_EQ(pin.head<10>(), expect);
  EXPECT_EQ(fromPinocchioOrder(pin), p);
  EXPECT_THROW(toPinocchioOrder(Eigen::VectorXd(7)), ModelError);
}

TEST(Parameters, NamesAndLayouts) {
  const Model model = planarArm(2);
  const auto names = model.parameterNames({true, true});
  ASSERT_EQ(names.size(), 26u);
  EXPECT_EQ(names[0], "XX1");
  EXPECT_EQ(names[9], "M1");
  EXPECT_EQ(names[10], "Ia1");
  EXPECT_EQ(names[11], "Fv1");
  EXPECT_EQ(names[12], "Fc1");
  EXPECT_EQ(names[13], "XX2");
  EXPECT_EQ(ParameterLayout::fromSize(2, 24).friction, true);
  EXPECT_EQ(ParameterLayout::fromSize(2, 24).rotor, false);
  EXPECT_THROW(ParameterLayout::fromSize(2, 25), ModelError);
}

TEST(Yaml, DhAndMdhDescribeTheSameArm) {
  // The same 3R arm as classic DH and as modified DH: the tool poses agree.
  const std::string dh = R"(
convention: dh
angle_unit: deg
joints:
  - {a: 0.1, alpha: 90, d: 0.4, theta: 0}
  - {a: 0.5, alpha: 0, d: 0, theta: 30}
  - {a: 0.3, alpha: -90, d: 0.1, theta: 0}
)";
  const std::string mdh = R"(
convention: mdh
angle_unit: deg
joints:
  - {alpha: 0, d: 0, theta: 0, r: 0.4}
  - {alpha: 90, d: 0.1, theta: 30, r: 0}
  - {alpha: 0, d: 0.5, theta: 0, r: 0.1}
tool: {xyz: [0.3, 0, 0], rpy: [-90, 0, 0]}
)";
  const Model a = parseYaml(dh), b = parseYaml(mdh);
  std::mt19937 rng(7);
  for (int t = 0; t < 5; ++t) {
    const Eigen::VectorXd q = test::random(rng, 3, 3);
    Eigen::Isometry3d Ta = Eigen::Isometry3d::Identity(), Tb = Eigen::Isometry3d::Identity();
    for (int k = 0; k < 3; ++k) {
      Ta = Ta * a.joints[k].transform(q[k]);
      Tb = Tb * b.joints[k].transform(q[k]);
    }
    EXPECT_LT((Ta.matrix() - (Tb * b.tool).matrix()).norm(), 1e-12);
  }
}

TEST(Yaml, ErrorsNameTheProblem) {
  EXPECT_TRUE(
      contains(errorOf<FileError>([] { loadYaml("/no/such/robot.yaml"); }), "/no/such/robot.yaml"));
  EXPECT_TRUE(
      contains(errorOf<ModelError>([] { parseYaml("joints: [", "x.yaml"); }), "not valid YAML"));
  EXPECT_TRUE(
      contains(errorOf<ModelError>([] { parseYaml("convention: dh\njoints: []\n", "x.yaml"); }),
               "'joints' must be a non-empty list"));
  EXPECT_TRUE(
      contains(errorOf<ModelError>([] { parseYaml("convention: xyz\njoints: [{}]\n", "x.yaml"); }),
               "'convention' must be 'dh' or 'mdh'"));
  const std::string typo = errorOf<ModelError>(
      [] { parseYaml("convention: dh\njoints:\n  - {a: 1, alfa: 2}\n", "x.yaml"); });
  EXPECT_TRUE(contains(typo, "unknown key 'alfa'")) << typo;
  EXPECT_TRUE(contains(typo, "x.yaml:3")) << typo;
  EXPECT_TRUE(contains(typo, "joint 1")) << typo;
  const std::string type = errorOf<ModelError>(
      [] { parseYaml("convention: dh\njoints:\n  - {type: ball}\n", "x.yaml"); });
  EXPECT_TRUE(contains(type, "'ball' is not supported (revolute, continuous, prismatic, spherical"))
      << type;
  const std::string num =
      errorOf<ModelError>([] { parseYaml("convention: dh\njoints:\n  - {a: abc}\n", "x.yaml"); });
  EXPECT_TRUE(contains(num, "'a' must be a number")) << num;
  const std::string lim = errorOf<ModelError>(
      [] { parseYaml("convention: dh\njoints:\n  - {limits: {lower: 1, upper: 0}}\n", "x.yaml"); });
  EXPECT_TRUE(contains(lim, "lower limit above upper limit")) << lim;
}

namespace {
const char* kTreeUrdf = R"(<robot name="tree">
  <link name="base"/>
  <link name="a"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="b"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="c"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="a"/><child link="b"/><origin xyz="1 0 0"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="j3" type="prismatic"><parent link="a"/><child link="c"/><origin xyz="0 1 0"/><axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>)";
}

TEST(Urdf, TreeLoadsWholeAndTipSelectsTheChain) {
  const Model t = parseUrdf(kTreeUrdf, "", "tree.urdf");
  ASSERT_EQ(t.nq(), 3);
  EXPECT_EQ(t.parents, (std::vector<int>{-1, 0, 0}));
  EXPECT_EQ(t.link_names, (std::vector<std::string>{"base", "a", "b", "c"}));
  EXPECT_EQ(t.joints[2].type, JointType::Prismatic);
  EXPECT_TRUE(t.joints[2].pre.translation().isApprox(Eigen::Vector3d(0, 1, 0)));
  EXPECT_TRUE(t.tool.isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_TRUE(t.notes.empty()) << t.notes;
  const Model m = parseUrdf(kTreeUrdf, "c", "tree.urdf");
  ASSERT_EQ(m.nq(), 2);
  EXPECT_TRUE(m.parents.empty());  // a chain: the serial representation
  EXPECT_EQ(m.joints[1].type, JointType::Prismatic);
  EXPECT_EQ(m.inertial[9], 2.0);  // a + the locked branch b
  EXPECT_TRUE(
      contains(errorOf<ModelError>([] { parseUrdf(kTreeUrdf, "nope", "tree.urdf"); }), "nope"));
}

namespace {
std::string massAt(double m, const std::string& xyz) {
  return "<inertial><origin xyz=\"" + xyz + "\"/><mass value=\"" + std::to_string(m) +
         "\"/><inertia ixx=\"0\" iyy=\"0\" izz=\"0\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>";
}
std::string joint(const std::string& name, const std::string& type, const std::string& parent,
                  const std::string& child, const std::string& xyz = "0 0 0") {
  return "<joint name=\"" + name + "\" type=\"" + type + "\"><origin xyz=\"" + xyz +
         "\"/><parent link=\"" + parent + "\"/><child link=\"" + child +
         "\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" " +
         "velocity=\"1\"/></joint>";
}
}  // namespace

// Joints depth-first, siblings by joint name (not document order); fixed joints fold into the
// origin of the next moving joint and their subtrees without moving joints into the body above;
// links before the first moving joint are the base.
TEST(Urdf, TreeOrderParentsAndFixedJoints) {
  const std::string xml =
      "<robot name=\"t\"><link name=\"world\"/><link name=\"torso\">" + massAt(5, "0 0 0") +
      "</link><link name=\"a\">" + massAt(1, "0 0 0") + "</link><link name=\"sensor\">" +
      massAt(2, "0 0 0.5") + "</link><link name=\"mount\">" + massAt(3, "0 0 0") +
      "</link><link name=\"b\">" + massAt(1, "0 0 0") + "</link><link name=\"c\">" +
      massAt(1, "0 0 0") + "</link><link name=\"d\">" + massAt(1, "0 0 0") + "</link>" +
      // written out of order: the order comes from the names
      joint("z_right", "revolute", "torso", "d", "0 -1 0") +
      joint("y_mount", "fixed", "a", "mount", "1 0 0") +
      joint("x_sensor", "fixed", "a", "sensor", "0 2 0") +
      joint("m_left", "revolute", "torso", "a", "0 1 0") +
      joint("b_wrist", "prismatic", "mount", "c", "0 0 1") +
      joint("c_elbow", "continuous", "a", "b", "0 0 3") +
      joint("a_torso", "fixed", "world", "torso", "0 0 1") + "</robot>";
  const Model m = parseUrdf(xml, "", "t.urdf");
  ASSERT_EQ(m.nq(), 4);
  std::vector<std::string> names;
  for (const Joint& j : m.joints) names.push_back(j.name);
  // under a: c_elbow (moving) before y_mount (fixed, with b_wrist below); then z_right
  EXPECT_EQ(names, (std::vector<std::string>{"m_left", "c_elbow", "b_wrist", "z_right"}));
  EXPECT_EQ(m.parents, (std::vector<int>{-1, 0, 0, -1}));
  EXPECT_EQ(m.link_names, (std::vector<std::string>{"world", "a", "b", "c", "d"}));
  EXPECT_TRUE(m.joints[0].pre.translation().isApprox(Eigen::Vector3d(0, 1, 1)));   // torso folded
  EXPECT_TRUE(m.joints[2].pre.translation().isApprox(Eigen::Vector3d(1, 0, 1)));   // mount folded
  EXPECT_TRUE(m.joints[3].pre.translation().isApprox(Eigen::Vector3d(0, -1, 1)));  // the base
  EXPECT_EQ(m.joints[2].type, JointType::Prismatic);
  // body a = a (1 kg at 0) + sensor (2 kg at (0, 2, 0.5)) + mount (3 kg at (1, 0, 0))
  const Eigen::Matrix<double, 10, 1> a = m.inertial.segment<10>(0);
  EXPECT_DOUBLE_EQ(a[9], 6.0);
  EXPECT_TRUE(a.segment<3>(6).isApprox(Eigen::Vector3d(3, 4, 1))) << a.transpose();
  EXPECT_NEAR(a[0], 2 * (4 + 0.25), 1e-12);  // XX = sum m (y^2 + z^2)
  EXPECT_NEAR(a[4], -2 * 2 * 0.5, 1e-12);    // YZ = -sum m y z
  for (int k = 1; k < 4; ++k) EXPECT_DOUBLE_EQ(m.inertial[10 * k + 9], 1.0);
  EXPECT_TRUE(m.tool.isApprox(Eigen::Isometry3d::Identity()));
  // the chain to c through the same fixed joints: b is locked and merged into a
  const Model c = parseUrdf(xml, "c", "t.urdf");
  ASSERT_EQ(c.nq(), 2);
  EXPECT_TRUE(c.parents.empty());
  EXPECT_DOUBLE_EQ(c.inertial[9], 7.0);
  EXPECT_TRUE(c.joints[1].pre.translation().isApprox(Eigen::Vector3d(1, 0, 1)));
}

// A mimic joint has no place in a model: locked and merged when it ends a branch (a gripper's
// mirrored finger), refused when moving joints hang below it or a chain's tip lies past it.
TEST(Urdf, MimicJointsAreLockedOrRefusedAndUnsupportedTypesNamed) {
  const std::string mimic =
      "<joint name=\"j3\" type=\"prismatic\"><parent link=\"a\"/><child "
      "link=\"c\"/><axis xyz=\"0 0 1\"/><mimic joint=\"j2\"/><limit "
      "lower=\"0.5\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>";
  const std::string links =
      "<robot name=\"t\"><link name=\"base\"/><link name=\"a\"/>"
      "<link name=\"b\"/><link name=\"c\">" +
      massAt(2, "0 0 0") + "</link>";
  const std::string two = joint("j1", "revolute", "base", "a") + joint("j2", "revolute", "a", "b");
  // a chain and a mimic leaf: j3 locked at its lower limit 0.5, c's mass merged into a
  const Model m = parseUrdf(links + two + mimic + "</robot>", "", "m.urdf");
  ASSERT_EQ(m.nq(), 2);
  EXPECT_TRUE(m.parents.empty());
  EXPECT_EQ(m.inertial[9], 2.0);
  EXPECT_TRUE(m.inertial.segment<3>(6).isApprox(Eigen::Vector3d(0, 0, 1.0)));  // 2 kg at z 0.5
  EXPECT_TRUE(contains(m.notes, "locked") && contains(m.notes, "'j3'")) << m.notes;
  // a tree (another branch d off the base) with the same mimic leaf
  const Model t = parseUrdf(links + "<link name=\"d\"/>" + two + mimic +
                                joint("j4", "revolute", "base", "d") + "</robot>",
                            "", "m.urdf");
  ASSERT_EQ(t.nq(), 3);
  EXPECT_EQ(t.parents, (std::vector<int>{-1, 0, -1}));
  EXPECT_EQ(t.inertial[9], 2.0);
  EXPECT_TRUE(contains(t.notes, "mimic joints locked") && contains(t.notes, "'j3'")) << t.notes;
  // moving joints below the mimic joint: refused, with or without a tip through it
  const std::string below =
      links + "<link name=\"e\"/>" + two + mimic + joint("j5", "revolute", "c", "e") + "</robot>";
  for (const char* tip : {"", "e"}) {
    const std::string e = errorOf<ModelError>([&] { parseUrdf(below, tip, "m.urdf"); });
    EXPECT_TRUE(contains(e, "m.urdf: joint 'j3' mimics joint 'j2', which is not supported")) << e;
    EXPECT_TRUE(contains(e, "tip")) << e;
  }
  const std::string planar =
      links + two + "<joint name=\"j3\" type=\"planar\"><parent link=\"a\"/><child link=\"c\"/>" +
      "</joint></robot>";
  // a planar joint (formerly refused) is a planar joint of the model
  const Model p = parseUrdf(planar, "", "p.urdf");
  EXPECT_EQ(p.joints.back().type, JointType::Planar);
  EXPECT_EQ(p.configSize(), p.nq() - 1 + 4);
}

TEST(Urdf, ErrorsNameTheProblem) {
  EXPECT_TRUE(contains(errorOf<FileError>([] { loadUrdf("/no/such.urdf"); }), "/no/such.urdf"));
  EXPECT_TRUE(contains(
      errorOf<ModelError>([] { parseUrdf("<robot name='x'><link", "", "bad.urdf"); }), "bad.urdf"));
  const char* floating = R"(<robot name="f"><link name="w"/><link name="b"/>
    <joint name="free" type="floating"><parent link="w"/><child link="b"/></joint></robot>)";
  // a floating joint (formerly refused) is a free-flyer: q of 7, v of 6
  const Model f = parseUrdf(floating, "", "f.urdf");
  EXPECT_EQ(f.joints[0].type, JointType::FreeFlyer);
  EXPECT_EQ(f.configSize(), 7);
  EXPECT_EQ(f.velocitySize(), 6);
}

namespace {
std::string revolute(const std::string& name, const std::string& parent, const std::string& child,
                     const std::string& extra = "") {
  return "<joint name=\"" + name + "\" type=\"revolute\"><parent link=\"" + parent +
         "\"/><child link=\"" + child + "\"/><axis xyz=\"0 0 1\"/>" + extra +
         "<limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>";
}
std::string robot(const std::string& links, const std::string& joints) {
  std::string s = "<robot name=\"r\"><link name=\"base\"/>";
  for (char l : links) s += std::string("<link name=\"") + l + "\"/>";
  return s + joints + "</robot>";
}
}  // namespace

TEST(Urdf, LoopsAndSelfParentedJointsAreNamed) {
  // a -> b -> c -> a beside the root: urdfdom accepts it (one link without a parent), the chain
  // walk would never end.
  const std::string loop = robot("abcd", revolute("j0", "base", "d") + revolute("j1", "a", "b") +
                                             revolute("j2", "b", "c") + revolute("j3", "c", "a"));
  for (const char* tip : {"", "c", "d"}) {
    const std::string e = errorOf<ModelError>([&] { parseUrdf(loop, tip, "loop.urdf"); });
    EXPECT_TRUE(contains(e,
                         "loop.urdf: joints 'j1', 'j2', 'j3' form a loop through links 'b', "
                         "'c', 'a'"))
        << e;
  }
  // base -> a -> b -> a: link a has two parent joints (here urdfdom's tree has a cycle of
  // children).
  const std::string two = robot(
      "ab", revolute("j0", "base", "a") + revolute("j1", "a", "b") + revolute("j2", "b", "a"));
  for (const char* tip : {"", "b"}) {
    const std::string e = errorOf<ModelError>([&] { parseUrdf(two, tip, "two.urdf"); });
    EXPECT_TRUE(contains(e, "two.urdf: link 'a' is the child of 2 joints ('j0', 'j2')")) << e;
  }
  // a joint that is its own parent's parent: b -> b
  const std::string self = robot("ab", revolute("j0", "base", "a") + revolute("j1", "b", "b"));
  const std::string e = errorOf<ModelError>([&] { parseUrdf(self, "", "self.urdf"); });
  EXPECT_TRUE(contains(e, "self.urdf: joint 'j1' has link 'b' as both its parent and its child"))
      << e;
  // the same chain without the bad joint loads
  EXPECT_EQ(parseUrdf(robot("a", revolute("j0", "base", "a")), "", "ok.urdf").nq(), 1);
}

TEST(Urdf, ExtremeValuesAreRefusedWithTheBound) {
  const std::string mass =
      "<inertial><mass value=\"M\"/><inertia ixx=\"1\" iyy=\"1\" izz=\"1\" "
      "ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>";
  auto withMass = [&](const std::string& m) {
    std::string link = mass;
    link.replace(link.find('M'), 1, m);
    return "<robot name=\"r\"><link name=\"base\"/><link name=\"a\">" + link + "</link>" +
           revolute("j0", "base", "a") + "</robot>";
  };
  // at the bound: accepted, and the gravity torque stays finite
  const Model ok = parseUrdf(withMass("1e16"), "", "m.urdf");
  EXPECT_EQ(ok.inertial[9], 1e16);
  const std::string e = errorOf<ModelError>([&] { parseUrdf(withMass("1e300"), "", "m.urdf"); });
  EXPECT_TRUE(contains(e,
                       "m.urdf:1: link 'a': <inertial><mass value=\"1e300\">: exceeds the "
                       "bound 1e+16"))
      << e;
  const std::string far = robot("a", revolute("j0", "base", "a", "<origin xyz=\"1e308 0 0\"/>"));
  const std::string o = errorOf<ModelError>([&] { parseUrdf(far, "", "o.urdf"); });
  EXPECT_TRUE(contains(o,
                       "o.urdf:1: joint 'j0': <origin xyz=\"1e308 0 0\">: \"1e308\" exceeds "
                       "the bound 1e+16"))
      << o;
}

TEST(Urdf, NumbersThatCannotBeReadAreRefusedWhereTheyAre) {
  // urdfdom logs these and keeps the link with mass and inertia 0, or takes a misspelt
  // attribute as absent
  auto withInertial = [](const std::string& inertial) {
    return "<robot name=\"r\">\n<link name=\"base\"/>\n<link name=\"a\">" + inertial + "</link>\n" +
           revolute("j0", "base", "a") + "</robot>";
  };
  const std::string inertia =
      "<inertia ixx=\"1\" iyy=\"1\" izz=\"1\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/>";
  struct Case {
    std::string inertial, expect;
  };
  const Case cases[] = {
      {"<inertial><mass value=\"3.7.0\"/>" + inertia + "</inertial>",
       "t.urdf:3: link 'a': <inertial><mass value=\"3.7.0\">: not a number"},
      {"<inertial><mass value=\"1\"/><inertia ixx=\"nan\" iyy=\"1\" izz=\"1\" ixy=\"0\" ixz=\"0\" "
       "iyz=\"0\"/></inertial>",
       "t.urdf:3: link 'a': <inertial><inertia ixx=\"nan\">: not a finite number"},
      {"<inertial><mass value=\"1\"/><inertia ixxx=\"1\" iyy=\"1\" izz=\"1\" ixy=\"0\" ixz=\"0\" "
       "iyz=\"0\"/></inertial>",
       "t.urdf:3: link 'a': <inertial><inertia> has an attribute ixxx=\"1\", which URDF does not "
       "define there; is it ixx?"},
      {"<inertial ixx=\"1\"><mass value=\"1\"/>" + inertia + "</inertial>",
       "t.urdf:3: link 'a': <inertial> has an attribute ixx=\"1\""},
  };
  for (const Case& c : cases) {
    const std::string e =
        errorOf<ModelError>([&] { parseUrdf(withInertial(c.inertial), "", "t.urdf"); });
    EXPECT_TRUE(contains(e, c.expect)) << e;
  }
  // white space around a number is read (XML Schema's xs:double), not taken as 0
  const Model spaced =
      parseUrdf(withInertial("<inertial><mass value=\" 2.5 \"/>" + inertia + "</inertial>"));
  EXPECT_EQ(spaced.inertial[9], 2.5);
  // a link without <inertial> is massless, and the notes say so
  const Model massless = parseUrdf(withInertial(""));
  EXPECT_TRUE(massless.inertial.isZero(0.0));
  EXPECT_TRUE(contains(massless.notes, "links without <inertial>, taken as massless: 'a'"))
      << massless.notes;
}

TEST(Yaml, TypeErrorsNameFileLineAndKey) {
  const std::string base = "name: r\nconvention: dh\njoints:\n  - {a: 1}\n";
  struct Case {
    std::string yaml, expect;
  };
  const Case cases[] = {
      {"name: [1, 2]\nconvention: dh\njoints:\n  - {a: 1}\n", "y.yaml:1:7: 'name' must be text"},
      {"name: r\nconvention: {x: 1}\njoints:\n  - {a: 1}\n",
       "y.yaml:2:13: 'convention' must be text"},
      {"name: r\nconvention: dh\njoints: {a: 1}\n",
       "y.yaml:3:9: 'joints' must be a non-empty list"},
      {"name: r\nconvention: dh\njoints:\n  - {a: [1]}\n",
       "y.yaml:4:9: joint 1 ('joint1'): 'a' must be a number, got a list"},
      {"name: r\nconvention: dh\njoints:\n  - {type: {x: 1}}\n",
       "y.yaml:4:12: joint 1 ('joint1'): 'type' must be text, got a mapping"},
      {"name: !!python/object:os.system r\nconvention: dh\njoints:\n  - {a: 1}\n",
       "y.yaml:1:7: YAML tag 'tag:yaml.org,2002:python/object:os.system' is not supported"},
      {"name: r\nconvention: dh\nname: s\njoints:\n  - {a: 1}\n",
       "y.yaml:3:1: key 'name' appears twice"},
      {"name: r\nconvention: dh\njoints:\n  - {a: 1, a: 2}\n",
       "y.yaml:4:12: key 'a' appears twice"},
      {"name: r\nconvention: dh\nsynthetic_inertia: maybe\njoints:\n  - {a: 1}\n",
       "y.yaml:3:20: 'synthetic_inertia' must be true or false"},
      {base + "---\n" + base, "y.yaml:5:1: a second YAML document starts here"},
      // yaml-cpp reads a quote left open as text running to the end of the file
      {"name: \"r\nconvention: dh\njoints:\n  - {a: 1}\n",
       "y.yaml:1:7: not valid YAML: the quoted text starting here is never closed"},
      {"convention: dh\njoints:\n  - name: 'j\n    a: 1\n",
       "y.yaml:3:11: not valid YAML: the quoted text starting here is never closed"},
      // yaml-cpp's LoadAll loops forever, allocating, on this (a stray flow end)
      {", 0.1]}}\n", "y.yaml"},
  };
  for (const Case& c : cases) {
    const std::string e = errorOf<ModelError>([&] { parseYaml(c.yaml, "y.yaml"); });
    EXPECT_TRUE(contains(e, c.expect)) << e << "\nexpected: " << c.expect;
  }
  EXPECT_EQ(parseYaml(base, "y.yaml").nq(), 1);
}

TEST(Yaml, ExtremeValuesAreRefusedWithTheBound) {
  // 1e16 is the bound: accepted; 2e16 is refused with the value, the bound, file, line and
  // column (of the value: the entry starts at column 6 of "  - {ENTRY}")
  EXPECT_EQ(parseYaml("convention: dh\njoints:\n  - {a: 1e16}\n", "y.yaml").nq(), 1);
  const std::pair<std::string, std::string> entries[] = {
      {"a: 2e16", "2e16"},
      {"d: -1e308", "-1e308"},
      {"inertial: {mass: 1e300}", "1e300"},
      {"inertial: {mass: 1, inertia: {xx: 1e200}}", "1e200"},
      {"limits: {lower: -1e300, upper: 1}", "-1e300"},
      {"rotor_inertia: 1e17", "1e17"}};
  for (const auto& [entry, value] : entries) {
    const std::string e = errorOf<ModelError>([&] {
      parseYaml(std::string("convention: dh\njoints:\n  - {") + entry + "}\n", "y.yaml");
    });
    const std::string at = "y.yaml:3:" + std::to_string(6 + entry.find(value)) + ": ";
    EXPECT_TRUE(contains(e, at + "joint 1 ('joint1'): '")) << e << "\nexpected: " << at;
    EXPECT_TRUE(contains(e, "exceeds the bound 1e+16")) << e;
  }
  const std::string g = errorOf<ModelError>([] {
    parseYaml("convention: dh\ngravity: [0, 0, -1e200]\njoints:\n  - {a: 1}\n", "y.yaml");
  });
  EXPECT_TRUE(contains(g, "y.yaml:2:17: 'gravity' = -1e200 exceeds the bound")) << g;
}

TEST(Yaml, NumbersThatCannotBeReadOrAreLeftEmptyAreRefused) {
  for (const char* entry : {"a: 3.7.0", "a: '3,7'", "a: nan", "a: 1e400", "a: 0x10"}) {
    const std::string e = errorOf<ModelError>([&] {
      parseYaml(std::string("convention: dh\njoints:\n  - {") + entry + "}\n", "y.yaml");
    });
    EXPECT_TRUE(contains(e, "y.yaml:3:9: joint 1 ('joint1'): 'a' must be a number, got '")) << e;
  }
  // a key written without a value is a number left out, not its default (the column where
  // the value would be: after "KEY: ", the entry starting at column 6 of "  - {ENTRY}")
  const std::pair<std::string, std::string> empty[] = {
      {"a: ", "a: "}, {"a: ~", "a: "}, {"inertial: {mass: 1, inertia: {xx: }}", "xx: "}};
  for (const auto& [entry, key] : empty) {
    const std::string e = errorOf<ModelError>([&] {
      parseYaml(std::string("convention: dh\njoints:\n  - {") + entry + "}\n", "y.yaml");
    });
    const std::string at = "y.yaml:3:" + std::to_string(6 + entry.find(key) + key.size());
    EXPECT_TRUE(contains(e, at + ": joint 1 ('joint1'): '")) << e << "\nexpected: " << at;
    EXPECT_TRUE(contains(e, "' has no value; give a number, or leave the key out")) << e;
  }
}

TEST(Model, ValidateBoundsMagnitudesAndJointCount) {
  const std::string e = errorOf<ModelError>([] { planarArm(kMaxModelJoints + 1); });
  EXPECT_TRUE(contains(e, "at most 1000 joints, got 1001")) << e;
  EXPECT_EQ(planarArm(kMaxModelJoints).nq(), kMaxModelJoints);
  Model m = planarArm(2);
  m.gravity.z() = -1e200;
  EXPECT_TRUE(contains(errorOf<ModelError>([&] { m.validate(); }),
                       "gravity component -1e+200 exceeds the bound 1e+16"));
  m = planarArm(2);
  m.joints[1].limits.velocity = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(contains(errorOf<ModelError>([&] { m.validate(); }),
                       "joint 'joint2': velocity limit is not finite"));
  m = planarArm(2);
  m.inertial[10 + 9] = 1e300;
  EXPECT_TRUE(contains(errorOf<ModelError>([&] { m.validate(); }),
                       "link 'link2': inertial parameter M 1e+300 exceeds the bound 1e+18"));
}

TEST(Model, ValidateParentIndices) {
  Model m = planarArm(3);
  m.parents = {-1, 0, 0};  // a tree: joints 2 and 3 on link 1
  EXPECT_NO_THROW(m.validate());
  EXPECT_FALSE(m.isSerial());
  EXPECT_TRUE(m.supports(0, 2) && !m.supports(1, 2) && m.supports(2, 2));
  m.parents = {-1, 0};
  EXPECT_TRUE(
      contains(errorOf<ModelError>([&] { m.validate(); }), "2 parent indices for 3 joints"));
  m.parents = {-1, 2, 0};  // a parent after its child
  EXPECT_TRUE(contains(errorOf<ModelError>([&] { m.validate(); }),
                       "joint 'joint2': parent index 2 is not in [-1, 0]"));
  m.parents = {-2, 0, 1};
  EXPECT_TRUE(contains(errorOf<ModelError>([&] { m.validate(); }),
                       "joint 'joint1': parent index -2 is not in [-1, -1]"));
  m.parents = {-1, 0, 1};  // written out, a chain is still a chain
  EXPECT_NO_THROW(m.validate());
  EXPECT_TRUE(m.isSerial());
}

TEST(Yaml, MessagesStayOneLineOfUtf8) {
  // NUL bytes make yaml-cpp quote a stray byte in its message; names may hold line breaks
  const std::string nul = "n" + std::string(8, '\0') +
                          "ame: three\nconvention: mdh\nsynthetic_inertia: true\nnotes: modified "
                          "DH\njoints:\n  - {alpha:, d: 0.1, theta: 0, r: 0, inertial: {mass: 1, "
                          "com: [0.2, 0, 0]}}\n  - {alpha: 0, d: }\n";
  const std::string e = errorOf<ModelError>([&] { parseYaml(nul, "n.yaml"); });
  EXPECT_TRUE(contains(e, "n.yaml")) << e;
  EXPECT_FALSE(contains(e, "\n")) << e;
  EXPECT_NO_THROW(requireUtf8(e, "message"));
  EXPECT_EQ(escapeControl("a\nb\x01\xff\xc3\xa9"), "a\\nb\\x01\\xff\xc3\xa9");
  const std::string u = errorOf<ModelError>([] { parseYaml("name: r\xff\n", "u.yaml"); });
  EXPECT_TRUE(contains(u, "u.yaml:1: not UTF-8 text (byte 0xff at offset 7)")) << u;
}

namespace {

/// A planar arm of 3 joints with the motors of `T` (named a, b, c).
Model withTransmission(const Eigen::MatrixXd& T) {
  Model m = planarArm(3);
  m.transmission.format = "yaml";
  m.transmission.T = T;
  m.transmission.offset = Eigen::VectorXd::Zero(T.rows());
  m.transmission.torque_constant = Eigen::VectorXd::Constant(T.rows(), NAN);
  for (int i = 0; i < T.rows(); ++i) {
    m.transmission.motors.push_back(std::string(1, static_cast<char>('a' + i)));
    m.transmission.types.push_back("matrix");
  }
  return m;
}

}  // namespace

TEST(Transmission, ValidateNamesEachProblem) {
  Eigen::MatrixXd T = Eigen::MatrixXd::Identity(3, 3) * 50.0;
  EXPECT_NO_THROW(withTransmission(T).validate());
  Eigen::MatrixXd idle = T;
  idle.col(1).setZero();
  EXPECT_NE(errorOf<ModelError>([&] {
              withTransmission(idle).validate();
            }).find("no motor drives joint 'joint2'"),
            std::string::npos);
  Eigen::MatrixXd deficient = T;
  deficient.col(2) = deficient.col(0) + deficient.col(1);
  EXPECT_NE(
      errorOf<ModelError>([&] { withTransmission(deficient).validate(); }).find("rank deficient"),
      std::string::npos);
  Eigen::MatrixXd nan = T;
  nan(1, 2) = NAN;
  EXPECT_NE(errorOf<ModelError>([&] {
              withTransmission(nan).validate();
            }).find("motor 'b': its coefficient of joint 'joint3'"),
            std::string::npos);
  Model twice = withTransmission(T);
  twice.transmission.motors[2] = "a";
  EXPECT_NE(errorOf<ModelError>([&] { twice.validate(); }).find("must be unique"),
            std::string::npos);
}

TEST(Transmission, AMultiDofJointHasAZeroColumnAndTheRankIsTheOtherJoints) {
  // joint1 a free-flyer (a floating base): two motors drive joint2 and joint3
  const auto floating = [](const Eigen::MatrixXd& T) {
    Model m = withTransmission(T);
    m.joints[0].type = JointType::FreeFlyer;
    return m;
  };
  Eigen::MatrixXd T(2, 3);
  T << 0.0, 50.0, 0.0, 0.0, 10.0, 40.0;
  EXPECT_NO_THROW(floating(T).validate());
  Eigen::MatrixXd driven = T;
  driven(1, 0) = 2.0;
  const std::string e = errorOf<ModelError>([&] { floating(driven).validate(); });
  EXPECT_NE(e.find("joint 'joint1': a floating joint has several degrees of freedom"),
            std::string::npos)
      << e;
  Eigen::MatrixXd idle = T;
  idle.col(2).setZero();
  EXPECT_NE(errorOf<ModelError>([&] {
              floating(idle).validate();
            }).find("no motor drives joint 'joint3'"),
            std::string::npos);
  Eigen::MatrixXd deficient = T;
  deficient.col(2) = 2.0 * deficient.col(1);
  EXPECT_NE(errorOf<ModelError>([&] { floating(deficient).validate(); }).find("rank deficient"),
            std::string::npos);
  Eigen::MatrixXd one = T.bottomRows(1);  // one motor for two single-DOF joints
  EXPECT_NE(
      errorOf<ModelError>([&] { floating(one).validate(); }).find("1 motors cannot drive 2 joints"),
      std::string::npos);
}

TEST(Transmission, FourBarAndDifferentialMatricesFollowRosControlPositionMaps) {
  // joint -> actuator positions as ros_control documents them, with offsets o:
  // four-bar: a1 j1 (x1 - o1), a2 ((x1 - o1) + j2 (x2 - o2));
  // differential: a1 (j1 (x1 - o1) + j2 (x2 - o2)), a2 (j1 (x1 - o1) - j2 (x2 - o2))
  TransmissionGroup g{"w",          "FourBarLinkageTransmission",
                      {"j5", "j6"}, {"m5", "m6"},
                      {50.0, 40.0}, {1.5, 0.5},
                      {0.1, -0.2}};
  const Eigen::Vector2d x(0.3, -0.7), d = x - Eigen::Vector2d(0.1, -0.2);
  const Eigen::Vector2d fourbar(50.0 * 1.5 * d[0], 40.0 * (d[0] + 0.5 * d[1]));
  EXPECT_LT((g.matrix() * x + g.offsets() - fourbar).norm(), 1e-12);
  g.type = "DifferentialTransmission";
  const Eigen::Vector2d diff(50.0 * (1.5 * d[0] + 0.5 * d[1]), 40.0 * (1.5 * d[0] - 0.5 * d[1]));
  EXPECT_LT((g.matrix() * x + g.offsets() - diff).norm(), 1e-12);
}

TEST(Transmission, Pr2WristMatrixInvertsPr2MechanismModelsActuatorToJointMap) {
  // pr2_mechanism_model's WristTransmission, actuators (right, left), joints (flex, roll):
  // flex = (right / a_r - left / a_l) / (2 j_f), roll = (-right / a_r - left / a_l) / (2 j_r).
  const TransmissionGroup g{"w",          kPr2Wrist,   {"flex", "roll"}, {"r", "l"},
                            {60.0, 45.0}, {-1.0, 1.5}, {0.0, 0.0}};
  const Eigen::Vector2d x(0.3, -0.7);
  const Eigen::Vector2d m = g.matrix() * x;
  const double r = m[0] / 60.0, l = m[1] / 45.0;
  EXPECT_NEAR((r - l) / (2.0 * -1.0), x[0], 1e-12);
  EXPECT_NEAR((-r - l) / (2.0 * 1.5), x[1], 1e-12);
  EXPECT_EQ(g.offsets().norm(), 0.0);
}

TEST(Descriptions, FrictionVelocityErrorKeepsTheValueItRefuses) {
  // a small scale (-1e-7) was printed as -0.000000, which reads as a zero
  FrictionModel f;
  f.kind = FrictionKind::Smooth;
  f.velocity = Eigen::VectorXd::Constant(2, 1.0);
  f.velocity[1] = -1e-7;
  const std::string what = errorOf<ModelError>([&] { f.validate(2); });
  EXPECT_NE(what.find("velocity 2 must be positive"), std::string::npos) << what;
  EXPECT_NE(what.find("not -1e-07"), std::string::npos) << what;
  f.kind = FrictionKind::Stribeck;
  f.velocity[1] = 3e20;
  EXPECT_NE(errorOf<ModelError>([&] { f.validate(2); }).find("not 3e+20"), std::string::npos);
}
