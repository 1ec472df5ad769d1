// Mesh export: the binary glTF (.glb) layout read back byte by byte, and the OBJ/PLY paths.
#include "mesher/MeshIO.h"
#include "support/MeshShapes.h"
#include "support/TestUtil.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

using namespace vdbclay;
using namespace vdbclay::test;
using nlohmann::json;

namespace {

uint32_t u32(const std::vector<char>& bytes, std::size_t offset)
{
    REQUIRE(offset + 4 <= bytes.size());
    uint32_t v = 0;
    for (int i = 3; i >= 0; --i) v = (v << 8) | uint8_t(bytes[offset + std::size_t(i)]);
    return v;
}

/// Two separate tetrahedra, the first of material 1 ("default"), the second of material `second`.
Mesh twoMaterialMesh(MaterialId second)
{
    Mesh a = tetrahedronMesh({{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}}, 1);
    const Mesh b = tetrahedronMesh({{{3, -1, 2}, {5, -1, 2}, {3, 0.5f, 2}, {3, -1, 4.25f}}}, second);
    const uint32_t base = uint32_t(a.positions.size());
    a.positions.insert(a.positions.end(), b.positions.begin(), b.positions.end());
    a.normals.insert(a.normals.end(), b.normals.begin(), b.normals.end());
    a.materials.insert(a.materials.end(), b.materials.begin(), b.materials.end());
    for (auto t : b.triangles) a.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    return a;
}

struct Glb {
    json doc;
    std::vector<char> bin;
};

/// Parses and checks the container: header, chunk types, lengths and alignment.
Glb readGlb(const std::string& path)
{
    const std::vector<char> bytes = readBytes(path);
    REQUIRE(bytes.size() >= 20);
    CHECK(std::memcmp(bytes.data(), "glTF", 4) == 0);
    CHECK(u32(bytes, 4) == 2);
    CHECK(u32(bytes, 8) == bytes.size());
    CHECK(bytes.size() % 4 == 0);
    const uint32_t jsonLength = u32(bytes, 12);
    CHECK(u32(bytes, 16) == 0x4E4F534Au);
    CHECK(jsonLength % 4 == 0);
    REQUIRE(20 + std::size_t(jsonLength) <= bytes.size());
    const std::string text(bytes.data() + 20, jsonLength);
    const std::size_t end = text.find_last_not_of(' ');
    REQUIRE(end != std::string::npos);
    CHECK(text[end] == '}'); // padded with spaces only
    Glb glb;
    glb.doc = json::parse(text);
    const std::size_t binStart = 20 + jsonLength;
    if (binStart < bytes.size()) {
        const uint32_t binLength = u32(bytes, binStart);
        CHECK(u32(bytes, binStart + 4) == 0x004E4942u);
        CHECK(binLength % 4 == 0);
        CHECK(binStart + 8 + binLength == bytes.size());
        glb.bin.assign(bytes.begin() + long(binStart + 8), bytes.begin() + long(binStart + 8 + binLength));
    }
    return glb;
}

template <typename T> std::vector<T> readAccessor(const Glb& glb, std::size_t index, int components)
{
    const json& acc = glb.doc["accessors"][index];
    const json& view = glb.doc["bufferViews"][acc["bufferView"].get<std::size_t>()];
    const std::size_t offset = view["byteOffset"].get<std::size_t>() + acc.value("byteOffset", std::size_t(0));
    const std::size_t count = acc["count"].get<std::size_t>() * std::size_t(components);
    REQUIRE(offset % sizeof(T) == 0);
    REQUIRE(count * sizeof(T) <= view["byteLength"].get<std::size_t>());
    REQUIRE(offset + count * sizeof(T) <= glb.bin.size());
    std::vector<T> out(count);
    std::memcpy(out.data(), glb.bin.data() + offset, count * sizeof(T));
    return out;
}

using Tri = std::array<std::array<float, 3>, 3>;

} // namespace

TEST_CASE("writeMesh writes a valid two-material GLB", "[meshio]")
{
    MaterialTable materials;
    Material clay;
    clay.name = "clay";
    clay.color = {0.7f, 0.3f, 0.2f, 1.0f};
    const MaterialId clayId = materials.define(clay);
    const Mesh mesh = twoMaterialMesh(clayId);
    TempDir dir;
    const std::string path = dir.file("two.glb");
    writeMesh(mesh, materials, path);
    CHECK(dir.entries() == std::vector<std::string>{"two.glb"}); // no temporary left behind

    const Glb glb = readGlb(path);
    const json& doc = glb.doc;
    CHECK(doc["asset"]["version"] == "2.0");
    CHECK(doc["asset"]["generator"] == "VDBClay");
    REQUIRE(doc["buffers"].size() == 1);
    CHECK(doc["buffers"][0]["byteLength"].get<std::size_t>() <= glb.bin.size());
    CHECK(glb.bin.size() - doc["buffers"][0]["byteLength"].get<std::size_t>() < 4);
    CHECK(doc["scenes"][0]["nodes"] == json::array({0}));
    CHECK(doc["nodes"][0]["mesh"] == 0);
    REQUIRE(doc["meshes"].size() == 1);
    const json& prims = doc["meshes"][0]["primitives"];
    REQUIRE(prims.size() == 2);
    REQUIRE(doc["materials"].size() == 2);

    // The expected triangles per material, as position triples.
    std::map<std::string, std::multiset<Tri>> expected;
    for (const auto& t : mesh.triangles) {
        const MaterialId id = mesh.materials[t[0]];
        expected[materials.at(id).name].insert(Tri{mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]});
    }

    std::set<std::string> seen;
    for (const json& prim : prims) {
        CHECK(prim.value("mode", 4) == 4);
        const json& mat = doc["materials"][prim["material"].get<std::size_t>()];
        const std::string name = mat["name"];
        seen.insert(name);
        const std::vector<float> color = mat["pbrMetallicRoughness"]["baseColorFactor"];
        const MaterialId id = *materials.find(name);
        for (int i = 0; i < 4; ++i) CHECK(color[std::size_t(i)] == materials.at(id).color[std::size_t(i)]);

        const std::size_t posIndex = prim["attributes"]["POSITION"], nIndex = prim["attributes"]["NORMAL"],
                          iIndex = prim["indices"];
        const json& pos = doc["accessors"][posIndex];
        CHECK(pos["componentType"] == 5126);
        CHECK(pos["type"] == "VEC3");
        CHECK(pos["count"] == 4); // a tetrahedron's vertices
        CHECK(doc["accessors"][nIndex]["count"] == 4);
        CHECK(doc["accessors"][iIndex]["count"] == 12);
        CHECK(doc["accessors"][iIndex]["componentType"] == 5125);
        CHECK(doc["bufferViews"][doc["accessors"][posIndex]["bufferView"].get<std::size_t>()]["target"] == 34962);
        CHECK(doc["bufferViews"][doc["accessors"][iIndex]["bufferView"].get<std::size_t>()]["target"] == 34963);

        const std::vector<float> p = readAccessor<float>(glb, posIndex, 3);
        const std::vector<float> n = readAccessor<float>(glb, nIndex, 3);
        const std::vector<uint32_t> idx = readAccessor<uint32_t>(glb, iIndex, 1);
        // min/max are the bounds of the primitive's positions.
        const std::vector<float> mn = pos["min"], mx = pos["max"];
        for (int axis = 0; axis < 3; ++axis) {
            float lo = 1e30f, hi = -1e30f;
            for (std::size_t v = 0; v < p.size() / 3; ++v) {
                lo = std::min(lo, p[v * 3 + std::size_t(axis)]);
                hi = std::max(hi, p[v * 3 + std::size_t(axis)]);
            }
            CHECK(mn[std::size_t(axis)] == lo);
            CHECK(mx[std::size_t(axis)] == hi);
        }
        if (name == "clay") {
            CHECK(mn == std::vector<float>{3, -1, 2});
            CHECK(mx == std::vector<float>{5, 0.5f, 4.25f});
        } else {
            CHECK(mn == std::vector<float>{0, 0, 0});
            CHECK(mx == std::vector<float>{1, 1, 1});
        }
        for (std::size_t v = 0; v < n.size() / 3; ++v)
            CHECK(std::fabs(n[3 * v] * n[3 * v] + n[3 * v + 1] * n[3 * v + 1] + n[3 * v + 2] * n[3 * v + 2] - 1.0f) < 1e-5f);
        // The index data reproduces this material's triangles, winding included.
        std::multiset<Tri> got;
        for (std::size_t t = 0; t + 2 < idx.size(); t += 3) {
            Tri tri;
            for (int k = 0; k < 3; ++k) {
                REQUIRE(idx[t + std::size_t(k)] < p.size() / 3);
                for (int axis = 0; axis < 3; ++axis)
                    tri[std::size_t(k)][std::size_t(axis)] = p[idx[t + std::size_t(k)] * 3 + std::size_t(axis)];
            }
            got.insert(tri);
        }
        CHECK(got == expected[name]);
    }
    CHECK(seen == std::set<std::string>{"default", "clay"});
}

TEST_CASE("GLB of an empty mesh, upper-case extension, and refused paths", "[meshio]")
{
    TempDir dir;
    const MaterialTable materials;
    writeMesh(Mesh{}, materials, dir.file("empty.GLB"));
    const Glb glb = readGlb(dir.file("empty.GLB"));
    CHECK(glb.doc["asset"]["version"] == "2.0");
    CHECK(glb.bin.empty());
    CHECK_FALSE(glb.doc.contains("meshes"));

    const Mesh cube = cubeMesh(0.5);
    CHECK_THROWS_AS(writeMesh(cube, materials, dir.file("cube.stl")), MeshIOError);
    CHECK_THROWS_AS(writeMesh(cube, materials, dir.file("cube")), MeshIOError);
    CHECK_THROWS_AS(writeMesh(cube, materials, dir.file("missing/cube.glb")), MeshIOError);
    CHECK(dir.entries() == std::vector<std::string>{"empty.GLB"});
}

TEST_CASE("OBJ and PLY export still work", "[meshio]")
{
    TempDir dir;
    MaterialTable materials;
    const Mesh mesh = twoMaterialMesh(materials.define(Material{"clay", {0.7f, 0.3f, 0.2f, 1.0f}, 0.5f, {}}));
    writeMesh(mesh, materials, dir.file("m.obj"));
    writeMesh(mesh, materials, dir.file("m.ply"));
    CHECK(dir.entries() == std::vector<std::string>{"m.mtl", "m.obj", "m.ply"});
    // The OBJ names its materials file and each run of faces its material, which the file defines.
    const std::vector<char> mtlBytes = readBytes(dir.file("m.mtl"));
    const std::string mtl(mtlBytes.begin(), mtlBytes.end());
    CHECK(mtl.find("newmtl clay\nKd 0.7 0.3 0.2\nd 1\n") != std::string::npos);
    CHECK(mtl.find("newmtl default\n") != std::string::npos);

    std::istringstream obj(std::string(readBytes(dir.file("m.obj")).data(), readBytes(dir.file("m.obj")).size()));
    std::size_t v = 0, vn = 0, f = 0;
    std::vector<std::string> libraries, uses;
    for (std::string line; std::getline(obj, line);) {
        if (line.rfind("v ", 0) == 0) ++v;
        else if (line.rfind("vn ", 0) == 0) ++vn;
        else if (line.rfind("f ", 0) == 0) {
            ++f;
            CHECK_FALSE(uses.empty()); // every face follows a usemtl
        }
        else if (line.rfind("mtllib ", 0) == 0) libraries.push_back(line.substr(7));
        else if (line.rfind("usemtl ", 0) == 0) uses.push_back(line.substr(7));
    }
    CHECK(v == 8);
    CHECK(vn == 8);
    CHECK(f == 8);
    CHECK(libraries == std::vector<std::string>{"m.mtl"});
    std::sort(uses.begin(), uses.end());
    CHECK(uses == std::vector<std::string>{"clay", "default"});

    const std::vector<char> ply = readBytes(dir.file("m.ply"));
    const std::string text(ply.begin(), ply.end());
    REQUIRE(text.rfind("ply\nformat binary_little_endian 1.0\n", 0) == 0);
    const std::size_t header = text.find("end_header\n");
    REQUIRE(header != std::string::npos);
    CHECK(ply.size() == header + 11 + 8 * 28 + 8 * 13);
}

TEST_CASE("GLB primitives follow per-triangle materials when the mesh has them", "[meshio]")
{
    MaterialTable materials;
    Material clay;
    clay.name = "clay";
    const MaterialId clayId = materials.define(clay);
    Mesh mesh = twoMaterialMesh(1); // every vertex of material 1 ...
    mesh.triangleMaterials.assign(mesh.triangleCount(), 1);
    for (std::size_t t = 0; t < 3; ++t) mesh.triangleMaterials[t] = clayId; // ... but three clay triangles
    TempDir dir;
    writeMesh(mesh, materials, dir.file("split.glb"));
    const Glb glb = readGlb(dir.file("split.glb"));
    const json& primitives = glb.doc["meshes"][0]["primitives"];
    REQUIRE(primitives.size() == 2);
    std::size_t indices = 0;
    for (const auto& p : primitives) {
        const std::size_t count = glb.doc["accessors"][p["indices"].get<std::size_t>()]["count"].get<std::size_t>();
        const std::string name = glb.doc["materials"][p["material"].get<std::size_t>()]["name"];
        CHECK(count == 3 * (name == "clay" ? 3 : mesh.triangleCount() - 3));
        indices += count;
    }
    CHECK(indices == 3 * mesh.triangleCount());
}

TEST_CASE("OBJ positions round-trip to float precision far from the origin", "[meshio]")
{
    Mesh mesh;
    mesh.positions = {{10000.123f, -9999.877f, 0.3f}, {10000.5f, -9999.5f, 1.0f}, {10001.25f, -9998.75f, 2.0f}};
    mesh.normals.assign(3, {0.0f, 0.0f, 1.0f});
    mesh.materials.assign(3, 1);
    mesh.triangles = {{0, 1, 2}};
    TempDir dir;
    writeMesh(mesh, MaterialTable{}, dir.file("far.obj"));
    std::ifstream in(dir.file("far.obj"));
    std::string line;
    std::size_t v = 0;
    while (std::getline(in, line)) {
        if (line.rfind("v ", 0) != 0) continue;
        std::istringstream fields(line.substr(2));
        float x, y, z;
        fields >> x >> y >> z;
        REQUIRE(v < 3);
        CHECK(x == mesh.positions[v][0]); // bit-exact: 9 significant digits
        CHECK(y == mesh.positions[v][1]);
        CHECK(z == mesh.positions[v][2]);
        ++v;
    }
    CHECK(v == 3);
}
