#include <mgn/core/error.hpp>
#include <mgn/geometry/mesh_io.hpp>

#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Importer.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>

namespace mgn {

namespace fs = std::filesystem;

namespace {

Material read_material(const aiScene* scene, const aiMaterial* m, const fs::path& dir) {
  Material out;
  aiString name;
  if (m->Get(AI_MATKEY_NAME, name) == AI_SUCCESS) out.name = name.C_Str();
  aiColor4D c;
  if (m->Get(AI_MATKEY_BASE_COLOR, c) == AI_SUCCESS ||
      m->Get(AI_MATKEY_COLOR_DIFFUSE, c) == AI_SUCCESS) {
    out.base_color = Vec4f(c.r, c.g, c.b, c.a);
  }
  aiColor3D s;
  if (m->Get(AI_MATKEY_COLOR_SPECULAR, s) == AI_SUCCESS) out.specular = Vec3f(s.r, s.g, s.b);
  float value = 0.0f;
  // OBJ files without a .mtl (and `Ns 0`) report a shininess of 0: keep the default then.
  if (m->Get(AI_MATKEY_SHININESS, value) == AI_SUCCESS && std::isfinite(value) && value > 0.0f)
    out.shininess = value;
  if (m->Get(AI_MATKEY_OPACITY, value) == AI_SUCCESS && std::isfinite(value)) {
    out.opacity = std::clamp(value, 0.0f, 1.0f);
  } else if (m->Get(AI_MATKEY_TRANSPARENCYFACTOR, value) == AI_SUCCESS && std::isfinite(value)) {
    out.opacity = std::clamp(1.0f - value, 0.0f, 1.0f);
  }
  if (out.base_color[3] < 1.0f) out.opacity = std::min(out.opacity, out.base_color[3]);
  // glTF 2.0 metallic-roughness factors (assimp's glTF2 importer; other formats have none).
  if (m->Get(AI_MATKEY_METALLIC_FACTOR, value) == AI_SUCCESS && std::isfinite(value)) {
    out.has_pbr = true;
    out.metallic = std::clamp(value, 0.0f, 1.0f);
    // glTF defaults: roughness 1 when the factor is absent.
    out.roughness = 1.0f;
  }
  if (m->Get(AI_MATKEY_ROUGHNESS_FACTOR, value) == AI_SUCCESS && std::isfinite(value)) {
    out.has_pbr = true;
    out.roughness = std::clamp(value, 0.0f, 1.0f);
  }
  if (m->Get(AI_MATKEY_TRANSMISSION_FACTOR, value) == AI_SUCCESS && std::isfinite(value)) {
    out.has_pbr = true;
    out.transmission = std::clamp(value, 0.0f, 1.0f);
  }
  if (out.has_pbr && m->Get(AI_MATKEY_REFRACTI, value) == AI_SUCCESS && std::isfinite(value) &&
      value >= 1.0f) {
    out.ior = value;
  }
  aiString tex;
  if (m->GetTexture(aiTextureType_BASE_COLOR, 0, &tex) == AI_SUCCESS ||
      m->GetTexture(aiTextureType_DIFFUSE, 0, &tex) == AI_SUCCESS) {
    if (const aiTexture* embedded = scene->GetEmbeddedTexture(tex.C_Str())) {
      if (embedded->mHeight == 0) {  // compressed image bytes (PNG/JPEG)
        const auto* bytes = reinterpret_cast<const std::uint8_t*>(embedded->pcData);
        out.texture_data.assign(bytes, bytes + embedded->mWidth);
      }
    } else {
      fs::path p(tex.C_Str());
      if (p.is_relative()) p = dir / p;
      out.texture_path = p.lexically_normal().string();
    }
  }
  return out;
}

/// Builds a Mesh from raw arrays of one sub-mesh, dropping (or rejecting) degenerate faces.
Mesh clean_part(Points3f v, Faces f, Points2f uv, std::vector<Material> mats, bool drop,
                const std::string& path) {
  const auto bad = find_degenerate_faces(v, f);
  if (!bad.empty()) {
    if (!drop) {
      throw_error<InvalidArgument>(
          "load_mesh('", path, "'): ", bad.size(), " face(s) have zero area (first: face ",
          bad.front(), "); expected non-degenerate triangles (or drop_degenerate=true)");
    }
    Faces kept(f.rows() - static_cast<Eigen::Index>(bad.size()), 3);
    Eigen::Index k = 0;
    std::size_t b = 0;
    for (Eigen::Index i = 0; i < f.rows(); ++i) {
      if (b < bad.size() && bad[b] == i) {
        ++b;
        continue;
      }
      kept.row(k++) = f.row(i);
    }
    f = std::move(kept);
  }
  return Mesh(std::move(v), std::move(f), std::move(uv), std::move(mats), {}, "");
}

// Fails with IoError unless path names an existing, readable file (not a directory).
void check_mesh_file(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw_error<IoError>("load_mesh: file not found: '", path, "'");
  if (fs::is_directory(path, ec)) {
    throw_error<IoError>("load_mesh: '", path, "' is a directory; expected a mesh file");
  }
  {
    std::ifstream probe(path, std::ios::binary);
    if (!probe) throw_error<IoError>("load_mesh: cannot open '", path, "' for reading");
  }
}

// One assimp sub-mesh as raw arrays, before cleaning: vertices (m, transformed by X and scaled),
// its triangles (wound outward for a mirroring X), texture coordinates (empty where absent or
// not finite) and its material.
struct Raw {
  Points3f v;
  Faces f;
  Points2f uv;
  std::vector<Material> mats;
};

Raw read_sub_mesh(const aiMesh* m, const aiMatrix4x4& X, const std::vector<Material>& materials,
                  double scale, const std::string& path) {
  Raw r;
  r.v.resize(m->mNumVertices, 3);
  for (unsigned k = 0; k < m->mNumVertices; ++k) {
    const aiVector3D p = X * m->mVertices[k];
    r.v.row(k) << static_cast<float>(p.x * scale), static_cast<float>(p.y * scale),
        static_cast<float>(p.z * scale);
    if (!r.v.row(k).allFinite()) {
      throw_error<InvalidArgument>("load_mesh('", path, "'): vertex ", k, " of sub-mesh '",
                                   m->mName.C_Str(),
                                   "' is not finite; expected finite coordinates");
    }
  }
  r.f.resize(m->mNumFaces, 3);
  Eigen::Index nf = 0;
  for (unsigned k = 0; k < m->mNumFaces; ++k) {
    if (m->mFaces[k].mNumIndices != 3) continue;
    for (int j = 0; j < 3; ++j) r.f(nf, j) = static_cast<std::int32_t>(m->mFaces[k].mIndices[j]);
    ++nf;
  }
  r.f.conservativeResize(nf, 3);
  if (X.Determinant() < 0) r.f.col(1).swap(r.f.col(2));  // mirroring node: keep outward winding
  if (m->HasTextureCoords(0)) {
    r.uv.resize(m->mNumVertices, 2);
    for (unsigned k = 0; k < m->mNumVertices; ++k)
      r.uv.row(k) << m->mTextureCoords[0][k].x, m->mTextureCoords[0][k].y;
    if (!r.uv.allFinite()) r.uv = Points2f();
  }
  if (m->mMaterialIndex < materials.size()) r.mats.push_back(materials[m->mMaterialIndex]);
  return r;
}

}  // namespace

Mesh load_mesh(const std::string& path, const LoadOptions& options) {
  if (!(options.scale > 0.0) || !std::isfinite(options.scale)) {
    throw_error<InvalidArgument>("load_mesh('", path, "'): scale must be finite and > 0, got ",
                                 options.scale);
  }
  check_mesh_file(path);

  Assimp::Importer importer;
  // Points and lines are dropped; the rest is triangulated. Vertices are joined only where every
  // attribute matches, so texture seams stay split (validation welds by position).
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const unsigned flags = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                         aiProcess_SortByPType | aiProcess_ValidateDataStructure;
  const aiScene* scene = importer.ReadFile(path, flags);
  if (scene == nullptr) {
    throw_error<IoError>("load_mesh: cannot read '", path,
                         "' as a mesh: ", importer.GetErrorString());
  }
  if (!scene->HasMeshes() || scene->mRootNode == nullptr) {
    throw_error<InvalidArgument>(
        "load_mesh('", path, "'): the file holds no triangle mesh; expected at least one triangle");
  }

  const fs::path dir = fs::path(path).parent_path();
  std::vector<Material> materials;  // by assimp material index
  for (unsigned i = 0; i < scene->mNumMaterials; ++i)
    materials.push_back(read_material(scene, scene->mMaterials[i], dir));
  // Raw sub-meshes may hold degenerate faces, which the Mesh constructor rejects: collect raw
  // arrays first, then clean.
  std::vector<Raw> raws;
  std::function<void(const aiNode*, const aiMatrix4x4&)> visit = [&](const aiNode* node,
                                                                     const aiMatrix4x4& parent) {
    const aiMatrix4x4 X = parent * node->mTransformation;
    for (unsigned i = 0; i < node->mNumMeshes; ++i) {
      const aiMesh* m = scene->mMeshes[node->mMeshes[i]];
      if (!(m->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) || m->mNumFaces == 0) continue;
      raws.push_back(read_sub_mesh(m, X, materials, options.scale, path));
    }
    for (unsigned c = 0; c < node->mNumChildren; ++c) visit(node->mChildren[c], X);
  };
  visit(scene->mRootNode, aiMatrix4x4());

  std::vector<Mesh> parts;
  for (auto& r : raws) {
    if (r.f.rows() == 0) continue;
    Mesh part = clean_part(std::move(r.v), std::move(r.f), std::move(r.uv), std::move(r.mats),
                           options.drop_degenerate, path);
    if (!part.empty()) parts.push_back(std::move(part));
  }
  if (parts.empty()) {
    throw_error<InvalidArgument>("load_mesh('", path,
                                 "'): the file holds no non-degenerate triangle; expected a mesh");
  }
  if (parts.size() > 1 && !options.merge) {
    throw_error<InvalidArgument>("load_mesh('", path, "'): the file holds ", parts.size(),
                                 " sub-meshes; pass merge=true to merge them into one mesh");
  }
  const std::string name = fs::path(path).stem().string();
  if (parts.size() == 1) {
    Mesh& m = parts.front();
    m.set_name(name);
    return std::move(m);
  }
  return Mesh::merge(parts, name);
}

}  // namespace mgn
