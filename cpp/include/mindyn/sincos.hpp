// Sine and cosine of one angle together, without a branch or a call for |x| <= 1e6: the routine
// of the run-time tapes, and the constants the C emitter writes into generated sources.
//
// x = k pi/2 + r with k the nearest integer, found by a truncating conversion of a positive
// number (no floating-point rounding trick that reassociation could undo), and |r| <= pi/4 + tiny;
// pi/2 is split in two parts, the first with 32 significant bits, so that k times it is exact for
// |k| < 2^21. On r, with z = r^2:
//   sin r = r + r z S(z),   cos r = (1 - z/2) + z^2 C(z),
// S and C of degree 5, interpolating (sin r - r)/(r z) and (cos r - 1 + z/2)/z^2 at the six
// Chebyshev nodes of z in [0, (pi/4)^2] (computed in 60-digit arithmetic; their own error is
// below 1e-17), evaluated in Estrin's scheme for a short dependency chain. The quadrant k mod 4
// selects (cos, sin) of k pi/2 from a table and the angle-sum formulas combine them. Within
// 2.2e-16 of the C library; beyond 1e6 rad, and for NaN and infinities, the C library's values.
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <cmath>

namespace mindyn {

namespace sincos_constants {
inline constexpr double kLimit = 1.0e6;
inline constexpr double kTwoOverPi = 0x1.45f306dc9c883p-1;
inline constexpr double kHalfPiHead = 0x1.921fb54400000p+0;   // 32 significant bits
inline constexpr double kHalfPiTail = 0x1.0b4611a626331p-34;  // pi/2 - kHalfPiHead
// k = (long)(x 2/pi + kOffset + 0.5) - kOffset: the argument of the conversion is positive
inline constexpr long kOffset = 2097152;
inline constexpr double kSin[6] = {-0x1.5555555555555p-3,  0x1.1111111110bb2p-7,
                                   -0x1.a01a019e83aaep-13, 0x1.71de37968a100p-19,
                                   -0x1.ae600b02b6262p-26, 0x1.5e0b19f8b1451p-33};
inline constexpr double kCos[6] = {0x1.5555555555555p-5,  -0x1.6c16c16c16967p-10,
                                   0x1.a01a019f4eb01p-16, -0x1.27e4fa17da09ep-22,
                                   0x1.1eeb68e93b64cp-29, -0x1.907da367a37cbp-37};
// (cos, sin) of k pi/2 for k mod 4
inline constexpr double kQuadrant[4][2] = {{1.0, 0.0}, {0.0, 1.0}, {-1.0, 0.0}, {0.0, -1.0}};
}  // namespace sincos_constants

/// s = sin(x), c = cos(x).
inline void sinCos(double x, double& s, double& c) noexcept {
  using namespace sincos_constants;
  if (!(std::abs(x) <= kLimit)) {
    s = std::sin(x);
    c = std::cos(x);
    return;
  }
  const long k = static_cast<long>(x * kTwoOverPi + (static_cast<double>(kOffset) + 0.5)) - kOffset;
  const double kd = static_cast<double>(k);
  const double r = (x - kd * kHalfPiHead) - kd * kHalfPiTail;
  const double z = r * r, z2 = z * z, z4 = z2 * z2;
  const double sp =
      (kSin[0] + z * kSin[1]) + z2 * (kSin[2] + z * kSin[3]) + z4 * (kSin[4] + z * kSin[5]);
  const double cp =
      (kCos[0] + z * kCos[1]) + z2 * (kCos[2] + z * kCos[3]) + z4 * (kCos[4] + z * kCos[5]);
  const double sr = r + r * z * sp;
  const double cr = (1.0 - 0.5 * z) + z2 * cp;
  const double* const t = kQuadrant[static_cast<unsigned long>(k) & 3u];
  s = sr * t[0] + cr * t[1];
  c = cr * t[0] - sr * t[1];
}

}  // namespace mindyn
