// The editor's file menu beyond saving: meshes and standard level sets brought into the scene (as a tool
// stamped where they were, so the import is one undoable edit that replays), the scene exported as a
// mesh or a level set, and a box of it made into a tool.
#pragma once

#include "editor/EditingSession.h"
#include "sculpt/Brush.h"

#include <nlohmann/json.hpp>

#include <array>
#include <string>

namespace vdbclay {

/// Voxelizes a mesh (OBJ, PLY, glTF, STL, ...) or reads a standard .vdb level set on the scene's lattice,
/// saves it as a tool in SCENE.imports/ beside the scene, and returns the op that adds it in place
/// (apply it as a Command::Kind::ApplyOp). `material` names a scene material for every voxel (empty: the
/// mesh's own). Throws for unreadable or empty inputs.
nlohmann::json importIntoScene(const EditingSession& session, const std::string& path, const std::string& material);

/// The same for a model placed at `centre` (world units), scaled so that its bounding box's half
/// diagonal is `radius` (a library model found by the query panel, dropped at the brush).
nlohmann::json placeModelIntoScene(const EditingSession& session, const std::string& path, const std::array<double, 3>& centre, double radius,
                                   const std::string& material);

/// The scene (its autosaved state, level 0) as a mesh file (format from the extension) or as a standard
/// .vdb level set. Atomic.
void exportSceneMesh(EditingSession& session, const std::string& path);
void exportSceneLevelSet(EditingSession& session, const std::string& path);

/// The voxels of the scene whose centres lie in `box` (world units), saved as a tool .vdb; returns the
/// brush shape that stamps it ({"shape": "grid", "file": path}).
nlohmann::json makeToolFromBox(EditingSession& session, const WorldBounds& box, const std::string& path);

} // namespace vdbclay
