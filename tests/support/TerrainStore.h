// A synthetic terrain store with its levels of detail, as several test files stream and edit it.
#pragma once

#include "scene/SceneStore.h"
#include "scene/StoreLod.h"
#include "scene/Synthesize.h"
#include "support/TestUtil.h"

#include <cstdint>
#include <string>

namespace vdbclay::test {

/// `vdbclay synth terrain` of `extent` voxels and `seed` into `dir`/`name`, with `levels` coarse levels.
inline std::string terrainStore(const TempDir& dir, const std::string& name, int32_t extent, uint64_t seed, int levels)
{
    SynthOptions o;
    o.kind = SynthKind::Terrain;
    o.extent = extent;
    o.seed = seed;
    const std::string path = dir.file(name);
    synthesizeStore(o, path);
    SceneStore scene = SceneStore::open(path, StoreAccess::ReadWrite);
    buildStoreLod(scene, levels);
    return path;
}

} // namespace vdbclay::test
