// vdbclay index / query: a library of models searched by shape (src/query). `index add` reads meshes
// (Assimp, in a bounded child process each), draws their silhouettes and thumbnails (the renderer),
// computes the other descriptors in parallel and adds each model in a transaction of its own; `query`
// ranks the library's models by their distance to a mesh's or a scene's descriptors.
#include "Cli.h"

#include "mesher/LodMesh.h"
#include "mesher/Mesher.h"
#include "query/ModelLibrary.h"
#include "query/SceneModels.h"
#include "render/ImageFile.h"
#include "render/ModelViews.h"
#include "render/VulkanContext.h"
#include "scene/SceneStore.h"
#include "vdb_hermite/VolumeIO.h"
#include "voxelize/TriangleMesh.h"
#include "wavelet/LodPyramid.h"

#include <CLI/CLI.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <filesystem>
#include <iostream>

namespace vdbclay::cli {

namespace fs = std::filesystem;

IndexCommands addIndexCommand(CLI::App& parent, IndexOptions& o)
{
    CLI::App* index = parent.add_subcommand("index", "A library of 3D models to search by shape (see 'vdbclay query')");
    index->require_subcommand(1);
    IndexCommands c;
    c.add = index->add_subcommand("add", "Add meshes (obj ply stl off gltf glb fbx dae) to a library, made when it does not exist");
    c.add->add_option("library", o.library, "The library (an SQLite file; its search indexes are kept beside it)")->required()->type_name("LIBRARY");
    c.add->add_option("inputs", o.inputs, "Mesh files and folders of them")->required()->type_name("DIR_OR_FILES...");
    c.add->add_flag("--recursive", o.recursive, "Read the folders' subfolders too (a model's class is the folder it is in)");
    c.add->add_flag("--no-render", o.noRender,
                    "Make neither light fields nor thumbnails (no Vulkan device needed; such models are searched by clusterd2 and d2)");
    c.add->add_flag("--json", o.json, "Print {\"added\", \"already_there\", \"skipped\": [{\"path\", \"error\"}], \"models\", \"light_fields\"}");
    c.info = index->add_subcommand("info", "The models of a library");
    c.info->add_option("library", o.library, "The library")->required()->type_name("LIBRARY");
    c.info->add_flag("--json", o.json, "Print {\"models\": [{\"name\", \"class\", \"path\", \"triangles\", \"colour\"}], \"descriptors\": {\"clusterd2\", \"d2\", \"lightfield\": models holding it}}");
    c.remove = index->add_subcommand("remove", "Remove a model from a library");
    c.remove->add_option("library", o.library, "The library")->required()->type_name("LIBRARY");
    c.remove->add_option("name", o.name, "The model's name (as 'index info' lists it)")->required()->type_name("NAME");
    return c;
}

CLI::App* addQueryCommand(CLI::App& parent, QueryOptions& o)
{
    CLI::App* cmd = parent.add_subcommand("query", "The models of a library most like a mesh in shape");
    cmd->add_option("library", o.library, "The library ('vdbclay index add' makes one)")->required()->type_name("LIBRARY");
    cmd->add_option("input", o.input, "A mesh file, or a scene (.vdb or store), meshed with its materials' colours")->required()->type_name("INPUT");
    cmd->add_option("--lod", o.lod, "A scene: mesh its level of detail K (a store's built level; a .vdb's is built on the fly)")
        ->capture_default_str()
        ->check(CLI::Range(0, 12))
        ->type_name("K");
    cmd->add_option("-k", o.k, "How many models to list")->capture_default_str()->check(CLI::Range(std::size_t(1), std::size_t(100000)));
    cmd->add_option("--descriptor", o.descriptor,
                    "clusterd2 (salient points and colour edges, clustered), d2 (all distances), lightfield (silhouettes from a "
                    "dodecahedron) or combined (all three)")
        ->capture_default_str()
        ->check(CLI::IsMember({"clusterd2", "d2", "lightfield", "combined"}));
    cmd->add_option("--metric", o.metric, "chi2 (chi-square) or jsd (Jensen-Shannon), on smoothed histograms")
        ->capture_default_str()
        ->check(CLI::IsMember({"chi2", "jsd"}));
    cmd->add_option("--thumbnails", o.thumbnails, "Write each result's thumbnail to DIR as RANK-NAME.png")->type_name("DIR");
    cmd->add_flag("--json", o.json,
                  "Print {\"results\": [{\"rank\", \"name\", \"class\", \"path\", \"distance\", \"thumbnail\"}], \"descriptor\", \"metric\"}");
    return cmd;
}

namespace {

/// A scene (.vdb or store) as a model: its level `lod` meshed, coloured by its materials, the lattice's
/// facets smoothed away.
TriangleSoup sceneModel(const std::string& path, int lod)
{
    Mesh mesh;
    MaterialTable materials;
    if (isStorePath(path)) {
        const SceneStore scene = SceneStore::open(path, StoreAccess::ReadOnly);
        if (lod > scene.lodLevels())
            throw UsageError("'" + path + "' has " + std::to_string(scene.lodLevels()) + " coarse levels; run 'vdbclay lod build " + path + "'");
        mesh = meshVolume(scene.loadLevel(lod));
        materials = scene.materials();
    } else {
        const Volume volume = loadScene(path);
        if (lod == 0) {
            mesh = meshVolume(volume);
        } else {
            wavelet::LodPyramid pyramid(std::max(lod, wavelet::LodPyramid::levelsFor(volume)));
            pyramid.build(volume);
            mesh = meshLevel(volume, pyramid, lod, MeshOptions{});
        }
        materials = volume.materials();
    }
    if (mesh.triangles.empty()) throw std::runtime_error("'" + path + "' has no surface to search with");
    return query::smoothedSculpture(query::soupOfMesh(mesh, materials));
}

struct Found {
    std::string path, name, label;
};

/// A model's path as the library keeps it: absolute, so that the editor (or a query run elsewhere) finds
/// the file to place.
std::string absolutePath(const fs::path& p)
{
    std::error_code ec;
    const fs::path full = fs::absolute(p, ec);
    return (ec ? p : full).lexically_normal().string();
}

/// The mesh files the inputs name: files as given, folders' meshes (their subfolders' with --recursive),
/// sorted, each with a name (its path under the folder, without extension) and a class (its folder).
std::vector<Found> findMeshes(const IndexOptions& o)
{
    std::vector<Found> out;
    for (const std::string& input : o.inputs) {
        std::error_code ec;
        if (fs::is_directory(input, ec)) {
            std::vector<fs::path> files;
            const auto visit = [&](const fs::directory_entry& e) {
                if (e.is_regular_file(ec) && isMeshPath(e.path().string())) files.push_back(e.path());
            };
            if (o.recursive)
                for (const auto& e : fs::recursive_directory_iterator(input, ec)) visit(e);
            else
                for (const auto& e : fs::directory_iterator(input, ec)) visit(e);
            std::sort(files.begin(), files.end());
            for (const fs::path& f : files) {
                const fs::path relative = fs::relative(f, input, ec);
                const std::string name = (relative.parent_path() / relative.stem()).generic_string();
                const std::string label = relative.has_parent_path() ? relative.parent_path().filename().string() : std::string();
                out.push_back({absolutePath(f), name, label});
            }
        } else if (fs::is_regular_file(input, ec)) {
            out.push_back({absolutePath(input), fs::path(input).stem().string(), ""});
        } else {
            throw UsageError("'" + input + "' does not exist");
        }
    }
    return out;
}

} // namespace

namespace {

/// The renderer for light fields and thumbnails; none (with a line saying so) without a Vulkan device.
struct Views {
    std::unique_ptr<render::VulkanContext> context;
    std::unique_ptr<render::ModelViews> views;
};

Views openViews(bool quiet, const std::string& without)
{
    Views v;
    try {
        v.context = std::make_unique<render::VulkanContext>();
        v.views = std::make_unique<render::ModelViews>(*v.context);
    } catch (const std::exception& e) {
        if (!quiet) std::cerr << "vdbclay: " << without << " (" << e.what() << ")\n";
        v = Views{};
    }
    return v;
}

} // namespace

int runIndexAdd(const IndexOptions& o)
{
    const std::vector<Found> found = findMeshes(o);
    if (found.empty()) {
        printError("no mesh files (obj ply stl off gltf glb fbx dae) in " + std::string(o.inputs.size() == 1 ? "'" + o.inputs.front() + "'" : "the inputs") +
                   (o.recursive ? "" : " (folders inside are read with --recursive)"));
        return kExitFailure;
    }
    query::ModelLibrary library(o.library, true);
    Views views = o.noRender ? Views{} : openViews(o.json, "models are added without light fields or thumbnails");
    const auto progress = terminalProgress("index add", !o.json);
    nlohmann::json skipped = nlohmann::json::array();
    uint64_t added = 0, present = 0;
    // A batch of meshes is read one after the other (each in a bounded child process), drawn (the
    // renderer is one thread's), described on the CPU in parallel, and added one transaction each.
    const std::size_t batch = 8;
    for (std::size_t from = 0; from < found.size(); from += batch) {
        const std::size_t to = std::min(found.size(), from + batch);
        std::vector<TriangleSoup> meshes(to - from);
        std::vector<query::ModelDescription> descriptions(to - from);
        std::vector<std::string> errors(to - from);
        std::vector<bool> there(to - from, false);
        for (std::size_t i = from; i < to; ++i) {
            // A model of that name is there already (an add run again, or one that was stopped): kept.
            there[i - from] = library.contains(found[i].name);
            if (there[i - from]) {
                ++present;
                continue;
            }
            try {
                meshes[i - from] = loadTriangleMesh(found[i].path);
                if (views.views) query::describeViews(*views.views, meshes[i - from], descriptions[i - from]);
            } catch (const std::exception& e) {
                errors[i - from] = e.what();
            }
        }
        tbb::parallel_for(std::size_t(0), to - from, [&](std::size_t i) {
            if (!errors[i].empty() || there[i]) return;
            try {
                query::describeShape(meshes[i], descriptions[i]);
            } catch (const std::exception& e) {
                errors[i] = e.what();
            }
        });
        for (std::size_t i = from; i < to; ++i) {
            if (there[i - from]) {
                // kept as it is
            } else if (errors[i - from].empty()) {
                library.add(found[i].name, found[i].path, found[i].label, meshes[i - from], descriptions[i - from]);
                ++added;
            } else {
                if (!o.json) std::cerr << "vdbclay: skipped " << found[i].path << ": " << errors[i - from] << "\n";
                skipped.push_back({{"path", found[i].path}, {"error", errors[i - from]}});
            }
            progress(i + 1, found.size());
        }
    }
    const std::size_t total = library.models().size();
    if (o.json) printJson({{"added", added}, {"already_there", present}, {"skipped", skipped}, {"models", total}, {"light_fields", views.views != nullptr}});
    else
        std::cout << "added " << added << " of " << found.size() << " models to " << o.library << (present ? " (" + std::to_string(present) + " there already)" : "")
                  << ", " << total << " in all" << (skipped.empty() ? "" : "; " + std::to_string(skipped.size()) + " could not be read") << "\n";
    return added + present > 0 || skipped.empty() ? kExitOk : kExitFailure;
}

int runIndexInfo(const IndexOptions& o)
{
    const query::ModelLibrary library(o.library, false);
    const std::vector<query::ModelRecord> models = library.models();
    if (o.json) {
        nlohmann::json list = nlohmann::json::array();
        for (const auto& m : models)
            list.push_back({{"name", m.name}, {"class", m.label}, {"path", m.path}, {"triangles", m.triangles}, {"colour", m.colour}});
        nlohmann::json descriptors = nlohmann::json::object();
        for (const query::Descriptor d : query::kStoredDescriptors) descriptors[query::descriptorName(d)] = library.count(d);
        printJson({{"library", o.library}, {"models", list}, {"descriptors", descriptors}});
        return kExitOk;
    }
    std::string counts;
    for (const query::Descriptor d : query::kStoredDescriptors)
        counts += std::string(counts.empty() ? "" : ", ") + query::descriptorName(d) + " " + std::to_string(library.count(d));
    std::cout << o.library << ": " << models.size() << (models.size() == 1 ? " model" : " models") << " (descriptors: " << counts << ")\n";
    for (const auto& m : models)
        std::cout << "  " << m.name << (m.label.empty() ? "" : "  [" + m.label + "]") << "  " << m.triangles << " triangles  " << m.path << "\n";
    return kExitOk;
}

int runIndexRemove(const IndexOptions& o)
{
    query::ModelLibrary library(o.library, false);
    if (!library.remove(o.name)) {
        printError("no model named '" + o.name + "' in " + o.library + " (see 'vdbclay index info " + o.library + "')");
        return kExitFailure;
    }
    std::cout << "removed " << o.name << " from " << o.library << "\n";
    return kExitOk;
}

int runQuery(const QueryOptions& o)
{
    const query::ModelLibrary library(o.library, false);
    if (o.lod > 0 && isMeshPath(o.input)) throw UsageError("--lod goes with a scene (.vdb or store), not a mesh file");
    const query::Descriptor descriptor = *query::parseDescriptor(o.descriptor);
    const query::Metric metric = o.metric == "jsd" ? query::Metric::JensenShannon : query::Metric::ChiSquare;
    const TriangleSoup mesh = isMeshPath(o.input) ? loadTriangleMesh(o.input) : sceneModel(o.input, o.lod);
    query::ModelDescription description;
    query::describeShape(mesh, description);
    if (descriptor == query::Descriptor::LightField && library.count(query::Descriptor::LightField) == 0) {
        printError("the library '" + o.library + "' holds no light fields (its models were added with --no-render or without a Vulkan device)");
        return kExitFailure;
    }
    // The light field needs the renderer: drawn when the ranking uses it and the library holds any.
    if ((descriptor == query::Descriptor::LightField || descriptor == query::Descriptor::Combined) && library.count(query::Descriptor::LightField) > 0) {
        Views views = openViews(o.json || descriptor == query::Descriptor::LightField, "the ranking leaves the light field out");
        if (views.views) description.lightField = query::lightFieldDescriptor(*views.views, mesh);
        else if (descriptor == query::Descriptor::LightField) {
            printError("the light field needs a Vulkan device, and none is usable here (use --descriptor clusterd2 or d2)");
            return kExitFailure;
        }
    }
    const std::vector<query::QueryHit> hits = library.query(description, o.k, descriptor, metric);
    std::vector<std::string> thumbnails(hits.size());
    if (!o.thumbnails.empty()) {
        std::error_code ec;
        fs::create_directories(o.thumbnails, ec);
        if (ec) throw std::runtime_error("cannot make the folder '" + o.thumbnails + "': " + ec.message());
        for (std::size_t i = 0; i < hits.size(); ++i) {
            const std::string png = library.thumbnail(hits[i].model.id);
            if (png.empty()) continue; // added without a renderer
            std::string name = hits[i].model.name;
            std::replace(name.begin(), name.end(), '/', '-');
            thumbnails[i] = (fs::path(o.thumbnails) / (std::to_string(i + 1) + "-" + name + ".png")).string();
            render::writePng(render::decodeImage(png), thumbnails[i]);
        }
    }
    if (o.json) {
        nlohmann::json results = nlohmann::json::array();
        for (std::size_t i = 0; i < hits.size(); ++i) {
            nlohmann::json r = {{"rank", i + 1}, {"name", hits[i].model.name}, {"class", hits[i].model.label}, {"path", hits[i].model.path},
                                {"distance", hits[i].distance}};
            if (!thumbnails[i].empty()) r["thumbnail"] = thumbnails[i];
            results.push_back(r);
        }
        printJson({{"input", o.input}, {"descriptor", o.descriptor}, {"metric", o.metric}, {"results", results}});
        return kExitOk;
    }
    for (std::size_t i = 0; i < hits.size(); ++i)
        std::cout << (i + 1) << ". " << hits[i].model.name << (hits[i].model.label.empty() ? "" : "  [" + hits[i].model.label + "]") << "  "
                  << hits[i].distance << (thumbnails[i].empty() ? "" : "  " + thumbnails[i]) << "\n";
    if (hits.empty()) std::cout << "the library is empty\n";
    return kExitOk;
}

} // namespace vdbclay::cli
