#pragma once
// Mesh files of every format the farm reads: OBJ and PLY by our own readers (FILE:LINE errors),
// glTF/GLB, COLLADA (DAE), STL and FBX through Assimp. Part of enavi::world_import, not of the core
// worlds library, so nothing below the workers links Assimp.

#include <array>
#include <filesystem>
#include <string>

#include "worlds/placement.h"

namespace enavi::worlds {

struct MeshFormat {
  const char* extension;  ///< lower case, with the dot
  const char* name;
};
inline constexpr std::array<MeshFormat, 7> kMeshFormats = {{{".obj", "Wavefront OBJ"},
                                                            {".gltf", "glTF 2.0"},
                                                            {".glb", "glTF 2.0 binary"},
                                                            {".dae", "COLLADA"},
                                                            {".stl", "STL"},
                                                            {".ply", "PLY"},
                                                            {".fbx", "FBX"}}};

/// True if the file's extension (any case) is one of kMeshFormats.
bool IsMeshFile(const std::filesystem::path& path);
/// ".obj, .gltf, ...": for messages.
std::string MeshExtensions();

/// Reads a mesh file of any kMeshFormats format: its triangles (node transforms applied), with
/// the unit and up axis the file declares (DAE <unit>/<up_axis>, glTF: metres and y up by its
/// spec, FBX UnitScaleFactor/UpAxis). Refuses, naming the file: a file over kMaxFileBytes, more
/// than kMaxTriangles triangles, a non-finite or absurd coordinate, a bad index, a file the
/// library cannot parse, a file with no triangles.
ImportedMesh LoadMeshFile(const std::filesystem::path& path);

}  // namespace enavi::worlds
