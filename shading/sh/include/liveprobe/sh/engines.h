#pragma once
// The nine coefficients (and the lights) in other engines' conventions. Pure math: no I/O.
//
// ============================ ENGINE FRAMES (stated once) ==================================
// An engine's frame is the one in which that engine, given the same equirectangular panorama as
// its environment and background, shows each pixel in the same direction as liveprobe does
// (liveprobe/sh/sh.h: pixel (row i, column j) of a W x H equirect is the R&H direction with
// polar angle t = pi (i + 0.5) / H from +z and azimuth p = 2 pi (j + 0.5) / W from +x towards
// +y). Each is derived from the engine's own panorama lookup, u = column / W, v = row / H with
// v = 0 the top row of the file:
//
//   three.js  equirectUv(d): u = atan2(d.z, d.x) / 2pi + 0.5, up = +y (asin(d.y), flipY).
//             The equirect background and PMREM environment are cube render targets drawn with
//             that lookup and sampled without flip (isRenderTargetTexture).
//             => three (x, y, z) = (-x, z, -y) of R&H. A reflection (det -1).
//   WebXR     three.js's XREstimatedLight copies sphericalHarmonicsCoefficients straight into a
//             LightProbe, so the same frame and basis as three.js (the XR reference space:
//             right-handed, +y up).
//   Babylon   PanoramaToCubeMapTools.CalcProjectionSpherical: u = atan2(v.z, v.x) / 2pi + 0.5,
//             row from acos(v.y) with invertY, and the cube faces it fills map the tool's v to
//             world (v.z, -v.y, v.x) (CubeMapToSphericalPolynomialTools._FileFaces).
//             => Babylon (x, y, z) = (-y, z, -x) of R&H. A rotation (Babylon is left-handed).
//   Filament  cmgen: CubemapUtils::equirectangularToCubemap, u = atan2(s.x, s.z) / 2pi + 0.5,
//             up = +y, then mirrorCubemap (x -> -x, cmgen's default).
//             => Filament (x, y, z) = (y, z, -x) of R&H. A reflection.
//   Unity     Skybox/Panoramic ToRadialCoords: u = 0.5 - atan2(d.z, d.x) / 2pi, v up = +y.
//             => Unity (x, y, z) = (-x, z, y) of R&H. A rotation (Unity is left-handed).
//   glTF      liveprobe's own GL frame (liveprobe/sh/axes.h): (-y, z, x) of R&H, right-handed,
//             +y up, the default camera looking down -z at the panorama's centre. The
//             EXT_lights_image_based cube faces are written in OpenGL's face convention in it.
//
// Coefficient forms (k = 0..8 in liveprobe's order L00, L1-1, L10, L11, L2-2, L2-1, L20, L21, L22;
// L_k are the radiance coefficients of the environment turned into the engine's frame, in
// liveprobe's basis, liveprobe/sh/sh.h):
//   three, webxr  radiance L_k; the engine evaluates E(n) with the R&H constants, 1/pi in its BRDF.
//   babylon       SphericalHarmonics h_k = s_k A_l L_k / pi, s_k = -1 for k = 1, 3, 5, 7 (its
//                 basis carries the Condon-Shortley phase): the Lambertian radiance its
//                 environment textures hold, and SphericalPolynomial.FromHarmonics of it.
//   filament,     pre-scaled: sh_k = (A_l / pi) Y_k L_k, Y_k the basis constant of k, so that
//   unity         E(n) / pi = sh0 + sh1 y + sh2 z + sh3 x + sh4 xy + sh5 yz + sh6 (3z^2 - 1)
//                 + sh7 xz + sh8 (x^2 - y^2)   (Filament's Irradiance_SphericalHarmonics, Unity's
//                 SHEvalLinearL0L1 + SHEvalLinearL2 after the unity_SHAr.. packing).
//   gltf          irradianceCoefficients: s_k A_l L_k (irradiance, Babylon's basis, no 1/pi),
//                 as Babylon's EXT_lights_image_based loader reads them.
// ============================================================================================
#include <glm/glm.hpp>
#include <optional>
#include <string_view>

#include "liveprobe/sh/sh.h"

namespace lp {

enum class Engine { Three, WebXr, Babylon, Filament, Unity, Gltf };

/// "three", "webxr", "babylon", "filament", "unity", "gltf".
std::string_view engineName(Engine e);
std::optional<Engine> parseEngine(std::string_view name);

/// d_engine = engineFromWorld(e) * d_world (an orthogonal matrix; see the table above).
glm::mat3 engineFromWorld(Engine e);

/// Radiance coefficients of the environment in the engine's frame, liveprobe's basis:
/// rotateSh(radiance, engineFromWorld(e)).
Sh9 toEngineFrame(const Sh9& radiance, Engine e);

/// The pre-scaled form of Filament and Unity (above), from radiance coefficients in any frame.
Sh9 preScaledIrradiance(const Sh9& radiance);

/// Coefficients with the Condon-Shortley phase applied (k = 1, 3, 5, 7 negated); its own inverse.
Sh9 condonShortley(const Sh9& sh);

/// Babylon's SphericalPolynomial (x, y, z, xx, yy, zz, yz, zx, xy) of SphericalHarmonics h, as
/// SphericalPolynomial.FromHarmonics computes it (its constants, kept as it states them).
struct BabylonPolynomial {
  Rgb x, y, z, xx, yy, zz, yz, zx, xy;
};
BabylonPolynomial babylonPolynomial(const Sh9& harmonics);

}  // namespace lp
