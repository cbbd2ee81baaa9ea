#pragma once
// liveprobe SH core: nine spherical-harmonic coefficients of a distant environment and the
// irradiance they give (Ramamoorthi & Hanrahan, "An Efficient Representation for Irradiance
// Environment Maps", SIGGRAPH 2001). Pure math: no GL, no OpenCV, no I/O.
//
// ============================== THE CONVENTION (stated once) ===============================
// World axes ("R&H frame"): +z is up. A direction is
//     w = (x, y, z) = (sin t cos p, sin t sin p, cos t),
// t the polar angle from +z, p the azimuth measured from +x towards +y.
// Every panorama layout maps its pixels into this frame (liveprobe/sh/layout.h says how each
// does; the equirect layout, the one projected with exact separable integrals, is defined here:
//   W x H, any aspect: row i covers t in [pi i/H, pi (i+1)/H] (row 0 touches +z),
//   column j covers p in [2 pi j/W, 2 pi (j+1)/W]; pixel centres at i + 0.5, j + 0.5;
//   solid angle (2 pi / W)(cos t0 - cos t1), exact, summing to 4 pi.)
// the GL renderer converts from it to GL's y-up frame in exactly one place (liveprobe/sh/axes.h).
//
// Coefficient order (index k = l(l+1)+m, as Filament's SHindex):
//     k: 0    1     2    3    4     5     6    7    8
//        L00  L1-1  L10  L11  L2-2  L2-1  L20  L21  L22
// Real basis, with the paper's constants (shBasis):
//     Y00 = 0.282095
//     Y1-1 = 0.488603 y   Y10 = 0.488603 z   Y11 = 0.488603 x
//     Y2-2 = 1.092548 xy  Y2-1 = 1.092548 yz  Y21 = 1.092548 xz
//     Y20 = 0.315392 (3z^2 - 1)               Y22 = 0.546274 (x^2 - y^2)
//
// Radiance coefficients (what Sh9 holds unless a name says otherwise):
//     L_lm = integral over the sphere of L(w) Y_lm(w) dw
// estimated from an image as sum_i L_i Y_lm(w_i) dw_i, dw_i the pixel's exact solid angle
// (the solid angles of a full panorama sum to 4 pi). No 1/pi, no A_l, no normalisation here.
//
// Irradiance E(n) = integral of L(w) max(n.w, 0) dw = sum_lm A_l L_lm Y_lm(n), with the
// clamped-cosine factors A0 = pi, A1 = 2pi/3, A2 = pi/4, applied ONLY by toIrradiance() (and
// folded into the constants c1..c5 of the quadratic form). A diffuse surface of albedo rho shows
// radiance rho E / pi: the 1/pi is applied by the shader (and renderers), never here.
//
// Quadratic form (R&H eq. 12): E(n) = n4^T M n4, n4 = (x, y, z, 1), one symmetric 4x4 M per
// colour channel, built from the RADIANCE coefficients L_lm with
//     c1 = 0.429043 c2 = 0.511664 c3 = 0.743125 c4 = 0.886227 c5 = 0.247708.
// ============================================================================================
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <memory>
#include <numbers>
#include <string_view>
#include <vector>

namespace lp {

using Rgb = glm::vec3;

inline constexpr int kShCount = 9;

/// Names of the coefficients, in storage order (used by every file format of liveprobe).
inline constexpr std::array<std::string_view, kShCount> kShNames = {
    "L00", "L1-1", "L10", "L11", "L2-2", "L2-1", "L20", "L21", "L22"};

/// Band l of coefficient index k.
constexpr int shBand(int k) { return k == 0 ? 0 : (k < 4 ? 1 : 2); }

/// Index of a coefficient name ("L2-1"), or -1.
int shIndex(std::string_view name);

/// Nine RGB coefficients. A value type; what they mean (radiance L_lm, or irradiance A_l L_lm)
/// is stated by whoever returns one.
struct Sh9 {
  std::array<Rgb, kShCount> c{};

  Sh9& operator+=(const Sh9& o) {
    for (int k = 0; k < kShCount; ++k) c[k] += o.c[k];
    return *this;
  }
  Sh9& operator*=(float s) {
    for (auto& v : c) v *= s;
    return *this;
  }
  friend Sh9 operator+(Sh9 a, const Sh9& b) { return a += b; }
  friend Sh9 operator*(Sh9 a, float s) { return a *= s; }
  friend bool operator==(const Sh9&, const Sh9&) = default;
};

/// pi, stated once for the whole program.
inline constexpr double kPi = std::numbers::pi;

/// The basis constants of the convention above, stated once (every formula uses these names).
inline constexpr float kY00 = 0.282095f;  ///< Y00
inline constexpr float kY1 = 0.488603f;   ///< Y1-1 / y, Y10 / z, Y11 / x
inline constexpr float kY2 = 1.092548f;   ///< Y2-2 / xy, Y2-1 / yz, Y21 / xz
inline constexpr float kY20 = 0.315392f;  ///< Y20 / (3z^2 - 1)
inline constexpr float kY22 = 0.546274f;  ///< Y22 / (x^2 - y^2)

/// Whether every coefficient is a finite number (a frame of radiance near float's maximum sums
/// to infinity: callers refuse such coefficients rather than pass them on).
inline bool isFinite(const Sh9& sh) {
  for (const Rgb& c : sh.c)
    if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z)) return false;
  return true;
}

/// Clamped-cosine convolution factors A_l (l = 0, 1, 2).
inline constexpr float kA0 = float(kPi);
inline constexpr float kA1 = float(2.0 * kPi / 3.0);
inline constexpr float kA2 = float(kPi / 4.0);
constexpr float shCosineLobe(int band) { return band == 0 ? kA0 : (band == 1 ? kA1 : kA2); }

/// The nine basis functions at unit direction d (R&H frame), in storage order.
std::array<float, kShCount> shBasis(glm::vec3 d);

/// One pixel of a panorama seen as a sample of the sphere: a unit direction (R&H frame) and the
/// exact solid angle the pixel covers, in steradians (0 for pixels outside the panorama).
struct SphereSample {
  glm::vec3 dir;
  float solidAngle;
};

/// Radiance coefficients of an image: sum_i rgb_i Y(dir_i) solidAngle_i.
/// rgb: count pixels of linear RGB float, `pixelStride` floats apart (3 for packed RGB).
/// Accumulates in float blocks summed in double, so a 4K frame keeps ~1e-7 relative accuracy.
Sh9 projectSamples(const float* rgb, std::size_t pixelStride, const SphereSample* samples,
                   std::size_t count);

/// Irradiance coefficients A_l L_lm from radiance coefficients L_lm.
Sh9 toIrradiance(const Sh9& radiance);

/// E(n) from radiance coefficients as the basis sum  sum_lm A_l L_lm Y_lm(n).  n: unit normal.
glm::vec3 evalIrradiance(const Sh9& radiance, glm::vec3 n);

/// The three 4x4 matrices of R&H eq. 12 (red, green, blue), from radiance coefficients.
/// glm is column-major; M is symmetric, so M[i][j] == M[j][i].
std::array<glm::mat4, 3> irradianceMatrices(const Sh9& radiance);

/// E(n) = n4^T M n4, n4 = (n, 1), per channel. This is, term for term, the GLSL in
/// shading/gl/src/shaders.cpp (function shIrradiance): keep the two identical.
glm::vec3 evalIrradianceQuadratic(const std::array<glm::mat4, 3>& m, glm::vec3 n);

// ---- Rotation -------------------------------------------------------------------------------

/// Coefficients of the environment turned by the rotation R (R&H frame): a light that was in
/// direction d is in direction R d afterwards, L'(w) = L(R^T w). Band 1 turns as the vector
/// (L11, L1-1, L10) = (x, y, z); band 2 by the 5x5 matrix that maps the band-2 basis through R,
/// formed by a constant quadrature on the 12 icosahedron vertices (Band2Design; exact, since band
/// 2 is closed under rotation and the vertices integrate degree-4 products exactly).
/// R may be any orthogonal matrix, a reflection included (band 2 is even, band 1 linear): an
/// environment flipped top to bottom is rotateSh(L, diag(1, 1, -1)).
Sh9 rotateSh(const Sh9& radiance, const glm::mat3& rotation);

/// The constant matrices behind band-2 rotation: the 12 icosahedron vertices (a spherical
/// 5-design), the band-2 basis at each, Y2m(w_i), m = -2..2, and the projection back onto band 2,
/// (A^T A)^-1 A^T with A = basis, which is (4 pi / 12) A^T up to the basis constants' precision.
struct Band2Design {
  std::array<glm::vec3, 12> dirs;
  std::array<std::array<double, 5>, 12> basis;
  std::array<std::array<double, 12>, 5> projection;
};
const Band2Design& band2Design();

/// R = Rz(yaw) * Ry(pitch) * Rx(roll), angles in degrees, about the world axes (+z up): yaw
/// turns the environment about the vertical, pitch tilts it about +y, roll about +x.
glm::mat3 rotationYawPitchRoll(float yawDeg, float pitchDeg, float rollDeg);

// ---- Windowing against ringing ---------------------------------------------------------------

/// Per-band attenuation factors sigma_l applied to L_lm (sigma_0 is always 1).
struct BandWindow {
  float sigma1 = 1.0f;
  float sigma2 = 1.0f;
};

/// Hann window of width w (Sloan, "Stupid Spherical Harmonics Tricks", 2008):
/// sigma_l = (1 + cos(pi l / w)) / 2 for l < w, else 0. Larger w is milder; w -> inf is none.
BandWindow hannWindow(float w);

/// Coefficients with band l scaled by sigma_l.
Sh9 applyWindow(const Sh9& radiance, const BandWindow& window);

/// Smallest irradiance over the unit sphere, per channel, with the normal where it occurs.
struct MinIrradiance {
  glm::vec3 value;                  ///< min over n of E(n), per channel
  std::array<glm::vec3, 3> normal;  ///< where each channel's minimum lies
  float minOfChannels() const { return glm::min(value.x, glm::min(value.y, value.z)); }
};

/// Minimum of E(n) over the sphere: dense Fibonacci sampling (4096 normals) refined by projected
/// gradient descent on the quadratic form; accurate to ~1e-6 of the L00 scale.
MinIrradiance minIrradiance(const Sh9& radiance);

/// Result of the automatic window search.
struct AutoWindow {
  float width;  ///< Hann width w; +infinity when no window was needed
  BandWindow window;
};

/// The mildest Hann window (largest w) that keeps irradiance non-negative over the sphere in all
/// channels (bisection on w in [2, 4096]). For any non-negative radiance w = 2 qualifies.
AutoWindow autoWindow(const Sh9& radiance);

/// The window Filament's cmgen applies by default (`--sh-window=auto`, libs/ibl CubemapSH::
/// windowSH): sigma_l = (sin(x) / x)^4 with x = pi l / cutoff for l < cutoff, else 0.
BandWindow sincWindow(float cutoff);

/// cmgen's automatic cutoff, step for step: starting from 13 bands (4 * 3 + 1), for each channel
/// in turn, 16 bisection steps in [3, cutoff] (stopping once the interval is under 0.1 band)
/// keep the largest cutoff whose windowed irradiance has no negative value; the cutoff is the
/// smallest of the three. A map whose irradiance is already non-negative still gets a cutoff
/// near 12.8 (sigma1 0.960, sigma2 0.850): cmgen never leaves it unwindowed.
struct CmgenWindow {
  float cutoff;
  BandWindow window;
};
CmgenWindow cmgenWindow(const Sh9& radiance);

/// Rec. 709 luminance.
constexpr float luminance(glm::vec3 c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

}  // namespace lp
