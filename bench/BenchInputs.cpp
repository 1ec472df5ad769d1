// bench inputs: what large and hostile inputs cost (issue 36): session files of 400,000 objects parsed
// against nlohmann's own parse of the same text; a stroke of 100,000 points against the same stroke of
// 600 points and against OpenVDB stamping its spheres; a tangled stroke of 2,000 long segments; a
// material's 8192^2 picture scaled to its mipmaps against a full-size filter per level.
#include "BenchSuites.h"
#include "BenchUtil.h"

#include "editor/SessionCommand.h"
#include "render/ImageFile.h"
#include "render/MaterialTextures.h"
#include "sculpt/StrokeScript.h"
#include "vdb_hermite/StrictJson.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/Composite.h>
#include <openvdb/tools/LevelSetSphere.h>

#include <stb_image_resize.h>

#include <cmath>
#include <iostream>
#include <random>

namespace vdbclay::bench {

namespace {

struct Row {
    std::string what;
    double oursMs = 0.0;
    double baselineMs = -1.0; // < 0: none
    std::string baseline;
};

std::vector<std::array<double, 3>> arc(int points)
{
    std::vector<std::array<double, 3>> out;
    for (int i = 0; i < points; ++i) {
        const double a = M_PI * i / (points - 1);
        out.push_back({40.0 * std::cos(a), 40.0 * std::sin(a), 0.0});
    }
    return out;
}

std::string strokeScript(const std::vector<std::array<double, 3>>& path, double radius)
{
    return nlohmann::json{{"ops", {{{"mode", "add"}, {"brush", {{"shape", "sphere"}, {"radius", radius}}}, {"path", path}}}}}.dump();
}

double runScript(const std::string& text)
{
    return timeMs([&] {
        Volume v(1.0);
        runStrokeScript(v, parseStrokeScript(text));
    });
}

/// OpenVDB's way to a stroke: a sphere level set at each point, unioned into one grid.
double openvdbStamps(const std::vector<std::array<double, 3>>& points, double radius)
{
    return timeMs([&] {
        openvdb::FloatGrid::Ptr stroke;
        for (const auto& p : points) {
            auto sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(float(radius), openvdb::Vec3f(float(p[0]), float(p[1]), float(p[2])),
                                                                                   1.0f);
            if (!stroke) stroke = sphere;
            else openvdb::tools::csgUnion(*stroke, *sphere);
        }
    });
}

} // namespace

int benchInputs(bool json, bool quick)
{
    const int objects = quick ? 100000 : 400000;
    std::vector<Row> rows;

    // Sessions: empty objects (refused at the first), and undos (read whole).
    std::string empties = "{\"vdbclay_session\": 1, \"commands\": [";
    std::string undos = empties;
    for (int i = 0; i < objects; ++i) {
        empties += i ? ",{}" : "{}";
        undos += std::string(i ? "," : "") + "{\"frame\": 0, \"command\": \"undo\"}";
    }
    empties += "]}";
    undos += "]}";
    for (const std::pair<std::string, const std::string*>& session :
         {std::pair<std::string, const std::string*>{"session of " + std::to_string(objects) + " {} (refused)", &empties},
          std::pair<std::string, const std::string*>{"session of " + std::to_string(objects) + " undos", &undos}}) {
        const std::string& text = *session.second;
        Row row;
        row.what = session.first;
        row.oursMs = timeMs([&] {
            try {
                parseSessionRecord(text, "bench");
            } catch (const SessionError&) {
            }
        });
        row.baselineMs = timeMs([&] {
            const nlohmann::json parsed = nlohmann::json::parse(text);
            (void)parsed;
        });
        row.baseline = "nlohmann::json::parse alone";
        rows.push_back(row);
    }

    // Strokes: the same arc sampled 100,000 and 600 times; OpenVDB stamps the 600 points.
    const double radius = 6.0;
    const std::string dense = strokeScript(arc(quick ? 20000 : 100000), radius), sparse = strokeScript(arc(600), radius);
    rows.push_back({"stroke of " + std::to_string(quick ? 20000 : 100000) + " points (add, r = 6)", runScript(dense), openvdbStamps(arc(600), radius),
                    "OpenVDB: 600 sphere stamps, csgUnion"});
    rows.push_back({"the same stroke of 600 points", runScript(sparse), -1.0, ""});

    // A tangled stroke: long random segments crossing one region again and again.
    std::mt19937_64 random(3);
    std::uniform_real_distribution<double> coordinate(-100.0, 100.0);
    std::vector<std::array<double, 3>> tangle;
    for (int i = 0; i < (quick ? 500 : 2000); ++i) tangle.push_back({coordinate(random), coordinate(random), coordinate(random)});
    rows.push_back({"tangled stroke of " + std::to_string(tangle.size()) + " random points in 200^3 (add, r = 6)", runScript(strokeScript(tangle, radius)),
                    -1.0, ""});

    // A material's picture: 8192^2 (4096^2 quick) down to the 256^2 layer and its mipmaps.
    const int side = quick ? 4096 : 8192;
    render::Image picture;
    picture.width = picture.height = side;
    picture.rgba.resize(std::size_t(side) * std::size_t(side) * 4);
    for (std::size_t i = 0; i < picture.rgba.size(); ++i) picture.rgba[i] = uint8_t((i * 2654435761u) >> 24);
    ScratchDir dir("inputs");
    render::writePng(picture, (dir.path() / "big.png").string());
    MaterialTable table;
    Material m;
    m.name = "pictured";
    m.texture = "big.png";
    table.define(m);
    Row texture;
    texture.what = "material picture " + std::to_string(side) + "^2 to a 256^2 layer and mipmaps (read included)";
    texture.oursMs = timeMs([&] { (void)render::loadMaterialTextures(table, dir.path().string(), 256); });
    const render::Image read = render::readImage((dir.path() / "big.png").string());
    texture.baselineMs = timeMs([&] {
        std::vector<uint8_t> level;
        for (int s = 256; s >= 1; s /= 2) {
            level.resize(std::size_t(s) * std::size_t(s) * 4);
            stbir_resize_uint8_srgb(read.rgba.data(), side, side, 0, level.data(), s, s, 0, 4, 3, 0);
        }
    }) + timeMs([&] { (void)render::readImage((dir.path() / "big.png").string()); });
    texture.baseline = "read, then stb_image_resize from full size per level";
    rows.push_back(texture);

    if (json) {
        nlohmann::json out = jsonPreamble("inputs", quick);
        for (const Row& r : rows)
            out["rows"].push_back({{"what", r.what}, {"ms", r.oursMs}, {"baseline_ms", r.baselineMs < 0.0 ? nlohmann::json() : nlohmann::json(r.baselineMs)},
                                   {"baseline", r.baseline}});
        std::cout << out.dump() << std::endl;
        return 0;
    }
    printPreamble(std::cout, "inputs", quick);
    std::cout << "What large and hostile inputs cost, beside the plain parse or OpenVDB's way on the same data.\n\n";
    Table t;
    t.header = {"input", "ours", "baseline", "baseline is"};
    for (const Row& r : rows)
        t.rows.push_back({r.what, fixed(r.oursMs, 1) + " ms", r.baselineMs < 0.0 ? "" : fixed(r.baselineMs, 1) + " ms", r.baseline});
    t.print(std::cout);
    return 0;
}

} // namespace vdbclay::bench
