// A CAD export's mesh through assimp (station/scene.h): every node's meshes as triangles in
// the scene frame, marked as moving with the door or not.
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>

#include "station/scene.h"

namespace doorbench::station {
namespace {

struct ImportContext {
  const aiScene* scene = nullptr;
  double metres_per_unit = 1.0;
  const std::vector<std::string>* door_nodes = nullptr;
  std::vector<bool> found;
  const Colours* colours = nullptr;
  std::vector<MeshPart> parts;
};

void append_mesh(ImportContext& context, const aiMesh& mesh, const aiMatrix4x4& transform,
                 MeshPart& part) {
  aiMatrix3x3 normal_matrix(transform);
  normal_matrix.Inverse().Transpose();
  for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
    const aiFace& face = mesh.mFaces[f];
    if (face.mNumIndices != 3) continue;  // points and lines are not drawn
    for (unsigned k = 0; k < 3; ++k) {
      const unsigned index = face.mIndices[k];
      const aiVector3D p = transform * mesh.mVertices[index];
      aiVector3D n = mesh.HasNormals() ? normal_matrix * mesh.mNormals[index] : aiVector3D(0, 1, 0);
      n.NormalizeSafe();
      for (const float c : {p.x, p.y, p.z}) {
        part.positions_m.push_back(static_cast<float>(c * context.metres_per_unit));
      }
      for (const float c : {n.x, n.y, n.z}) part.normals.push_back(c);
    }
  }
}

void visit(ImportContext& context, const aiNode& node, const aiMatrix4x4& parent, bool moves,
           bool handle) {
  const std::string name = node.mName.C_Str();
  const auto& names = *context.door_nodes;
  if (const auto it = std::find(names.begin(), names.end(), name); it != names.end()) {
    moves = true;
    context.found[std::size_t(it - names.begin())] = true;
  }
  handle = handle || name == "handle";
  const aiMatrix4x4 transform = parent * node.mTransformation;
  if (node.mNumMeshes > 0) {
    MeshPart part;
    part.name = name.empty() ? "mesh" : name;
    part.moves_with_door = moves;
    part.rgb = handle  ? context.colours->handle
               : moves ? context.colours->door
                       : context.colours->cabinet;
    for (unsigned m = 0; m < node.mNumMeshes; ++m) {
      append_mesh(context, *context.scene->mMeshes[node.mMeshes[m]], transform, part);
    }
    if (part.vertex_count() > 0) context.parts.push_back(std::move(part));
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c) {
    visit(context, *node.mChildren[c], transform, moves, handle);
  }
}

}  // namespace

std::vector<MeshPart> import_mesh(const std::filesystem::path& file, double metres_per_unit,
                                  const std::vector<std::string>& door_nodes, bool names_required,
                                  const Colours& colours) {
  Assimp::Importer importer;
  const aiScene* scene =
      importer.ReadFile(file.string(), aiProcess_Triangulate | aiProcess_GenNormals |
                                           aiProcess_JoinIdenticalVertices | aiProcess_SortByPType);
  if (scene == nullptr || scene->mRootNode == nullptr ||
      (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0) {
    throw SceneError(file.string() + ": cannot read the mesh: " + importer.GetErrorString());
  }
  ImportContext context;
  context.scene = scene;
  context.metres_per_unit = metres_per_unit;
  context.door_nodes = &door_nodes;
  context.found.assign(door_nodes.size(), false);
  context.colours = &colours;
  visit(context, *scene->mRootNode, aiMatrix4x4(), door_nodes.empty(), false);
  if (context.parts.empty()) throw SceneError(file.string() + ": the mesh has no triangles");
  const bool none_found =
      std::none_of(context.found.begin(), context.found.end(), [](bool found) { return found; });
  for (std::size_t i = 0; i < door_nodes.size(); ++i) {
    if (!context.found[i] && names_required) {
      throw SceneError(file.string() + ": mesh.door_nodes: no node named '" + door_nodes[i] +
                       "' in the mesh");
    }
  }
  if (!names_required && none_found) {
    // No node named "door": the whole mesh is the door.
    for (MeshPart& part : context.parts) {
      part.moves_with_door = true;
      if (part.name != "handle") part.rgb = colours.door;
    }
  }
  return context.parts;
}

}  // namespace doorbench::station
