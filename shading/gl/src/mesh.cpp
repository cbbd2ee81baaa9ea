// Meshes made in memory: the UV sphere, OBJ text (vertices and faces), fitting to the view.
#include "liveprobe/gl/mesh.h"

#include <algorithm>
#include <charconv>
#include <cmath>

#include "liveprobe/sh/sh.h"

namespace lp {

Mesh makeUvSphere(int segments, int rings) {
  Mesh m;
  const float pi = float(kPi);
  for (int r = 0; r <= rings; ++r) {
    const float t = pi * float(r) / float(rings);  // from +y down
    for (int s = 0; s <= segments; ++s) {
      const float p = 2.0f * pi * float(s) / float(segments);
      const glm::vec3 n(std::sin(t) * std::sin(p), std::cos(t), std::sin(t) * std::cos(p));
      m.positions.push_back(n);
      m.normals.push_back(n);
      m.uvs.emplace_back(float(s) / float(segments), 1.0f - float(r) / float(rings));
    }
  }
  const auto row = std::uint32_t(segments + 1);
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const std::uint32_t a = r * row + s, b = a + row;
      if (r != 0) m.indices.insert(m.indices.end(), {a, b, a + 1});
      if (r != rings - 1) m.indices.insert(m.indices.end(), {a + 1, b, b + 1});
    }
  return m;
}

Mesh meshFromObjText(std::string_view text) {
  Mesh out;
  std::vector<std::uint32_t> face;
  auto number = [](std::string_view& rest, auto& value) {
    while (!rest.empty() && (rest.front() == ' ' || rest.front() == '\t')) rest.remove_prefix(1);
    const auto [end, ec] = std::from_chars(rest.data(), rest.data() + rest.size(), value);
    if (ec != std::errc()) return false;
    rest.remove_prefix(std::size_t(end - rest.data()));
    return true;
  };
  for (std::size_t at = 0, n = 1; at < text.size(); ++n) {
    const std::size_t eol = std::min(text.find('\n', at), text.size());
    std::string_view line = text.substr(at, eol - at);
    at = eol + 1;
    if (line.starts_with("v ")) {
      line.remove_prefix(2);
      glm::vec3 p;
      if (!number(line, p.x) || !number(line, p.y) || !number(line, p.z) ||
          !std::isfinite(p.x + p.y + p.z))
        throw MeshError("OBJ line " + std::to_string(n) + ": a vertex needs three finite numbers");
      out.positions.push_back(p);
    } else if (line.starts_with("f ")) {
      line.remove_prefix(2);
      face.clear();
      for (long v = 0; number(line, v);) {
        // v, v/vt, v/vt/vn or v//vn: only the vertex is read; negative counts from the end.
        const long index = v < 0 ? long(out.positions.size()) + v : v - 1;
        if (index < 0 || index >= long(out.positions.size()))
          throw MeshError("OBJ line " + std::to_string(n) + ": vertex " + std::to_string(v) +
                          " does not exist");
        face.push_back(std::uint32_t(index));
        while (!line.empty() && line.front() != ' ' && line.front() != '\t') line.remove_prefix(1);
      }
      for (std::size_t k = 2; k < face.size(); ++k)  // a fan
        out.indices.insert(out.indices.end(), {face[0], face[k - 1], face[k]});
    }
  }
  if (out.indices.empty()) throw MeshError("OBJ text has no triangles");
  // Smooth normals: each vertex the sum of its faces' area-weighted normals.
  out.normals.assign(out.positions.size(), glm::vec3(0.0f));
  for (std::size_t t = 0; t + 2 < out.indices.size(); t += 3) {
    const auto a = out.indices[t], b = out.indices[t + 1], c = out.indices[t + 2];
    const glm::vec3 nrm =
        glm::cross(out.positions[b] - out.positions[a], out.positions[c] - out.positions[a]);
    out.normals[a] += nrm, out.normals[b] += nrm, out.normals[c] += nrm;
  }
  for (auto& nrm : out.normals) {
    const float len = glm::length(nrm);
    nrm = len > 0 ? nrm / len : glm::vec3(0, 1, 0);
  }
  return out;
}

void fitToUnitSphere(Mesh& mesh) {
  if (mesh.positions.empty()) return;
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (const auto& p : mesh.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
  const glm::vec3 centre = 0.5f * (lo + hi);
  float radius = 0;
  for (const auto& p : mesh.positions) radius = std::max(radius, glm::length(p - centre));
  const float s = radius > 0 ? 1.0f / radius : 1.0f;
  for (auto& p : mesh.positions) p = (p - centre) * s;
}

}  // namespace lp
