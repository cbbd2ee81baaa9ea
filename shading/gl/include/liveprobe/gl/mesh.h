#pragma once
// Triangle meshes on the CPU: loading through assimp (OBJ, PLY, glTF 2.0, and whatever else it
// reads; where the build has assimp), OBJ text read without it, a built-in UV sphere, and
// fitting a model to the view. No GL here.
#include <cstdint>
#include <glm/glm.hpp>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace lp {

struct Mesh {
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;      ///< unit, one per position
  std::vector<glm::vec2> uvs;          ///< empty, or one per position
  std::vector<std::uint32_t> indices;  ///< triangles
  std::string albedoTexture;           ///< path of the material's base-colour texture, if any
  glm::vec3 albedo{0.8f};              ///< material base colour (multiplies the texture)

  std::size_t triangleCount() const { return indices.size() / 3; }
};

/// A unit UV sphere centred at the origin, its poles on the GL +y axis, with exact normals and
/// uv coordinates. `segments` around, `rings` from pole to pole.
Mesh makeUvSphere(int segments = 128, int rings = 64);

/// Loads a model with assimp: triangulated, hierarchy flattened, smooth normals generated when
/// the file has none. Throws lp::MeshError naming the file on a missing or unreadable file and
/// on a file with no triangles.
Mesh loadMesh(const std::string& path);

/// The vertices and faces of OBJ text (polygons as fans; texture coordinates, normals, groups and
/// materials ignored), with smooth normals: for builds without assimp (the GPU benchmark bakes
/// its model in). Throws lp::MeshError naming the line of a bad vertex or face.
Mesh meshFromObjText(std::string_view text);

/// Centres the mesh's bounding box at the origin and scales it to fit the unit sphere.
void fitToUnitSphere(Mesh& mesh);

struct MeshError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace lp
