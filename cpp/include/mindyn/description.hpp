// Robot descriptions given as a YAML DH / modified-DH table, and generated models.
//
// YAML schema (SI units; angles in `angle_unit`):
//   name, description, source, notes: text
//   convention: dh | mdh        dh:  Rot(z,theta) Trans(z,d) Trans(x,a) Rot(x,alpha)
//                               mdh: Rot(x,alpha) Trans(x,d) Rot(z,theta) Trans(z,r)
//                               (Khalil-Kleinfinger)
//   angle_unit: rad | deg       applies to alpha, theta and to revolute limits
//   gravity: [gx, gy, gz]       optional, default [0, 0, -9.81]
//   synthetic_inertia: bool     the inertial values are invented
//   joints: list of
//     name, type: revolute | continuous | prismatic, or the multi-DOF pairs spherical |
//           universal | cylindrical | planar | floating (model.hpp, JointType: axis z of the
//           joint frame; universal's second axis x; planar in the xy plane), which take no
//           limits, drive, rotor_inertia or friction
//     parent: 0 for the base or the number (1-based) of an earlier joint; default the joint
//           before (a serial chain)
//     dh: a, alpha, d, theta     mdh: alpha, d, theta, r   (theta / d resp. r is the joint offset)
//     limits: {lower, upper, velocity, acceleration, effort}
//     drive: {rated_torque, gear_ratio, torque_constant}   motor side; torque_constant in N m/A
//     inertial: {mass, com: [x,y,z], inertia: {xx, yy, zz, xy, xz, yz}}   about the COM, link axes
//           or  {XX, XY, XZ, YY, YZ, ZZ, MX, MY, MZ, M}                     about the link origin
//     rotor_inertia: Ia           friction: {viscous, coulomb}
//   tool: {xyz: [..], rpy: [..]}   optional flange frame in the last link frame
//   transmissions:                 optional motors (transmission.hpp): q_m = T q + offset
//     {matrix: [[..] n_m rows of n], motors: [names], offset: [..], torque_constant: [..]}
//     or a list of {name, joints: {joint name: coefficient, ...}, offset, torque_constant}
//
// The file is one UTF-8 YAML document with plain values, lists and mappings (no key twice in a
// mapping, no tags beyond YAML's core ones such as !!str); every number is finite with magnitude
// at most kMaxDescriptionValue (a key given without a value, `xx:`, is refused: leave the key out
// for its default); at most kMaxModelJoints joints.
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <string>

#include "mindyn/model.hpp"

namespace mindyn {

/// Loads a YAML description file. Throws FileError or ModelError (with the file and key named).
Model loadYaml(const std::string& path);

/// Parses YAML text; `source` names it in error messages.
Model parseYaml(const std::string& text, const std::string& source = "<string>");

/// A planar arm of n revolute joints with parallel axes and links of length `length` [m], mass
/// `mass` [kg] (uniform rods). With `vertical` the plane of motion contains gravity; otherwise
/// the joint axes are parallel to gravity (horizontal plane).
Model planarArm(int n, bool vertical = true, double length = 0.5, double mass = 2.0);

}  // namespace mindyn
