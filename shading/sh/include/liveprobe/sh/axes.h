#pragma once
// THE one place where the R&H world frame of liveprobe/sh/sh.h (+z up) meets GL's frame (+y up).
// Pure math (part of shading_sh): the renderer uses it for normals and the background, and the
// cube-map layout for OpenGL's face convention, whose directions are given in GL's frame.
//
//   GL (X, Y, Z) = (-y, z, x) of the world;   world (x, y, z) = (Z, -X, Y) of GL.
//
// In the default view the camera sits on GL +Z looking at the origin with GL +Y up, so:
//   - the panorama's up (+z) is the screen's up;
//   - straight ahead (GL -Z) is world -x: the centre column of an equirect, the centre of an
//     angular map;
//   - screen right (GL +X) is world -y: the columns right of the equirect's centre, the right
//     half of an angular map. The background therefore reads like the image file, unmirrored.
// This map is a reflection (determinant -1), because the equirect convention (p increasing with
// the column, measured from +x towards +y) describes the scene as seen mirrored from inside. The
// model is never mirrored: only lighting and background lookups go through this map, both the
// same way, so light comes from where the background shows it.
#include <glm/glm.hpp>

namespace lp::axes {

inline glm::vec3 glFromWorld(glm::vec3 w) { return {-w.y, w.z, w.x}; }
inline glm::vec3 worldFromGl(glm::vec3 g) { return {g.z, -g.x, g.y}; }

/// worldFromGl as a matrix (column-major, for a GLSL uniform): world = M * gl.
inline glm::mat3 worldFromGlMatrix() {
  return glm::mat3(glm::vec3(0, -1, 0),  // image of GL X
                   glm::vec3(0, 0, 1),   // image of GL Y
                   glm::vec3(1, 0, 0));  // image of GL Z
}

}  // namespace lp::axes
