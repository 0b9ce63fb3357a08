// Loading descriptions: errors that name the problem, parameter conversions checked against a
// direct mass-point integration, DH/MDH conventions, URDF chains.
#include <gtest/gtest.h>

#include <cmath>

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
      [] { parseYaml("convention: dh\njoints:\n  - {type: spherical}\n", "x.yaml"); });
  EXPECT_TRUE(contains(type, "'spherical' is not supported")) << type;
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

TEST(Urdf, TreeNeedsATipAndTipSelectsTheChain) {
  const std::string e = errorOf<ModelError>([] { parseUrdf(kTreeUrdf, "", "tree.urdf"); });
  EXPECT_TRUE(contains(e, "tip")) << e;
  EXPECT_TRUE(contains(e, "b") && contains(e, "c")) << e;
  const Model m = parseUrdf(kTreeUrdf, "c", "tree.urdf");
  ASSERT_EQ(m.nq(), 2);
  EXPECT_EQ(m.joints[1].type, JointType::Prismatic);
  EXPECT_TRUE(
      contains(errorOf<ModelError>([] { parseUrdf(kTreeUrdf, "nope", "tree.urdf"); }), "nope"));
}

TEST(Urdf, ErrorsNameTheProblem) {
  EXPECT_TRUE(contains(errorOf<FileError>([] { loadUrdf("/no/such.urdf"); }), "/no/such.urdf"));
  EXPECT_TRUE(contains(
      errorOf<ModelError>([] { parseUrdf("<robot name='x'><link", "", "bad.urdf"); }), "bad.urdf"));
  const char* floating = R"(<robot name="f"><link name="w"/><link name="b"/>
    <joint name="free" type="floating"><parent link="w"/><child link="b"/></joint></robot>)";
  const std::string e = errorOf<ModelError>([&] { parseUrdf(floating, "", "f.urdf"); });
  EXPECT_TRUE(contains(e, "floating")) << e;
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
  EXPECT_TRUE(contains(e, "m.urdf: link 'a': mass 1e+300 exceeds the bound 1e+16")) << e;
  const std::string far = robot("a", revolute("j0", "base", "a", "<origin xyz=\"1e308 0 0\"/>"));
  const std::string o = errorOf<ModelError>([&] { parseUrdf(far, "", "o.urdf"); });
  EXPECT_TRUE(contains(o, "o.urdf: joint 'j0': origin xyz 1e+308 exceeds the bound 1e+16")) << o;
}

TEST(Yaml, TypeErrorsNameFileLineAndKey) {
  const std::string base = "name: r\nconvention: dh\njoints:\n  - {a: 1}\n";
  struct Case {
    std::string yaml, expect;
  };
  const Case cases[] = {
      {"name: [1, 2]\nconvention: dh\njoints:\n  - {a: 1}\n", "y.yaml:1: 'name' must be text"},
      {"name: r\nconvention: {x: 1}\njoints:\n  - {a: 1}\n", "y.yaml:2: 'convention' must be text"},
      {"name: r\nconvention: dh\njoints: {a: 1}\n", "y.yaml:3: 'joints' must be a non-empty list"},
      {"name: r\nconvention: dh\njoints:\n  - {a: [1]}\n",
       "y.yaml:4: joint 1 ('joint1'): 'a' must be a number, got a list"},
      {"name: r\nconvention: dh\njoints:\n  - {type: {x: 1}}\n",
       "y.yaml:4: joint 1 ('joint1'): 'type' must be text, got a mapping"},
      {"name: !!python/object:os.system r\nconvention: dh\njoints:\n  - {a: 1}\n",
       "y.yaml:1: YAML tag 'tag:yaml.org,2002:python/object:os.system' is not supported"},
      {"name: r\nconvention: dh\nname: s\njoints:\n  - {a: 1}\n",
       "y.yaml:3: key 'name' appears twice"},
      {"name: r\nconvention: dh\njoints:\n  - {a: 1, a: 2}\n", "y.yaml:4: key 'a' appears twice"},
      {"name: r\nconvention: dh\nsynthetic_inertia: maybe\njoints:\n  - {a: 1}\n",
       "y.yaml:3: 'synthetic_inertia' must be true or false"},
      {base + "---\n" + base, "y.yaml:5: a second YAML document starts here"},
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
  // 1e16 is the bound: accepted; 2e16 is refused with the value, the bound, file and line
  EXPECT_EQ(parseYaml("convention: dh\njoints:\n  - {a: 1e16}\n", "y.yaml").nq(), 1);
  for (const char* entry : {"a: 2e16", "d: -1e308", "inertial: {mass: 1e300}",
                            "inertial: {mass: 1, inertia: {xx: 1e200}}",
                            "limits: {lower: -1e300, upper: 1}", "rotor_inertia: 1e17"}) {
    const std::string e = errorOf<ModelError>([&] {
      parseYaml(std::string("convention: dh\njoints:\n  - {") + entry + "}\n", "y.yaml");
    });
    EXPECT_TRUE(contains(e, "y.yaml:3: joint 1 ('joint1'): '")) << e;
    EXPECT_TRUE(contains(e, "exceeds the bound 1e+16")) << e;
  }
  const std::string g = errorOf<ModelError>([] {
    parseYaml("convention: dh\ngravity: [0, 0, -1e200]\njoints:\n  - {a: 1}\n", "y.yaml");
  });
  EXPECT_TRUE(contains(g, "y.yaml:2: 'gravity' = -1e200 exceeds the bound")) << g;
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
