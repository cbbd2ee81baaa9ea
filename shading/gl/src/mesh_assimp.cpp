// Models through assimp (OBJ, PLY, glTF 2.0 and whatever else it reads): the one file of
// liveprobe::gl that includes assimp, built where the build has it (not in the core-only one).
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <assimp/Importer.hpp>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "liveprobe/gl/mesh.h"

namespace lp {

namespace {

// assimp reads a coordinate it cannot parse ("nan", "1.2.3") as a number all the same, so an OBJ's
// vertex lines are checked first: every coordinate must be a whole, finite number.
void checkObjCoordinates(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    if (line.size() < 2 || line[0] != 'v' || (line[1] != ' ' && line[1] != 't' && line[1] != 'n'))
      continue;
    std::istringstream tokens(line.substr(line[1] == ' ' ? 1 : 2));
    for (std::string t; tokens >> t;) {
      char* end = nullptr;
      const double v = std::strtod(t.c_str(), &end);
      if (end != t.c_str() + t.size() || !std::isfinite(v))
        throw MeshError(path + ": line " + std::to_string(n) + ": coordinate '" + t +
                        "' is not a finite number");
    }
  }
}

}  // namespace

Mesh loadMesh(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw MeshError(path + ": no such file");
  std::string ext = std::filesystem::path(path).extension().string();
  for (auto& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".obj") checkObjCoordinates(path);
  Assimp::Importer importer;
  // Smooth normals are generated only where the file has none (assimp skips meshes with normals).
  const aiScene* scene = importer.ReadFile(
      path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_GenSmoothNormals |
                aiProcess_PreTransformVertices | aiProcess_SortByPType);
  if (!scene || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE)) {
    const std::string why = importer.GetErrorString();
    // assimp's words for a file that parsed but holds no faces.
    if (why.find("No output meshes") != std::string::npos ||
        why.find("no meshes") != std::string::npos)
      throw MeshError(path + ": model has no triangles (assimp: " + why + ")");
    throw MeshError(path + ": cannot read model (" + why + ")");
  }
  Mesh out;
  for (unsigned mi = 0; mi < scene->mNumMeshes; ++mi) {
    const aiMesh* am = scene->mMeshes[mi];
    if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) || !am->HasNormals()) continue;
    const auto base = std::uint32_t(out.positions.size());
    const bool uv = am->HasTextureCoords(0);
    for (unsigned v = 0; v < am->mNumVertices; ++v) {
      const glm::vec3 p(am->mVertices[v].x, am->mVertices[v].y, am->mVertices[v].z);
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        throw MeshError(path + ": vertex " + std::to_string(out.positions.size() + 1) +
                        " is not a finite number");
      out.positions.push_back(p);
      glm::vec3 n(am->mNormals[v].x, am->mNormals[v].y, am->mNormals[v].z);
      const float len = glm::length(n);
      out.normals.push_back(len > 0 && std::isfinite(len) ? n / len : glm::vec3(0, 1, 0));
      if (uv) out.uvs.emplace_back(am->mTextureCoords[0][v].x, am->mTextureCoords[0][v].y);
    }
    if (!uv && !out.uvs.empty()) out.uvs.resize(out.positions.size(), glm::vec2(0));
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices != 3) continue;
      for (int k = 0; k < 3; ++k) out.indices.push_back(base + face.mIndices[k]);
    }
    if (out.albedoTexture.empty() && am->mMaterialIndex < scene->mNumMaterials) {
      const aiMaterial* mat = scene->mMaterials[am->mMaterialIndex];
      aiString tex;
      if (mat->GetTexture(aiTextureType_BASE_COLOR, 0, &tex) == AI_SUCCESS ||
          mat->GetTexture(aiTextureType_DIFFUSE, 0, &tex) == AI_SUCCESS) {
        const std::string t = tex.C_Str();
        if (!t.empty() && t[0] != '*')  // '*n' is an embedded texture: not supported
          out.albedoTexture = (std::filesystem::path(path).parent_path() / t).string();
      }
      aiColor4D c;
      if (mat->Get(AI_MATKEY_COLOR_DIFFUSE, c) == AI_SUCCESS && (c.r + c.g + c.b) > 0)
        out.albedo = {c.r, c.g, c.b};
    }
  }
  // Meshes without uvs after one with uvs were padded above; uvs shorter than positions means
  // a uv-less mesh came first: drop uvs entirely then.
  if (out.uvs.size() != out.positions.size()) out.uvs.clear();
  if (out.indices.empty()) throw MeshError(path + ": model has no triangles");
  return out;
}

}  // namespace lp
