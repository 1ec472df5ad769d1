// The editor's query panel underneath (ModelSearch): the sculpture as the view shows it searches a model
// library on a thread of its own, and a found model is placed at the brush as one undoable edit.
#include "editor/EditingSession.h"
#include "editor/ModelSearch.h"
#include "editor/SessionWorker.h"
#include "query/SyntheticModels.h"
#include "support/CliRun.h"
#include "support/QuietSession.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <thread>

using namespace vdbclay;
using namespace vdbclay::test;

namespace {

/// Frames until the view shows every brick it wants (loads run on the session's loaders).
void settle(EditingSession& session)
{
    for (int i = 0; i < 400; ++i) {
        const FrameReport r = session.frame(0.01 * i, {640, 480});
        if (r.settled && !session.scene().shownBricks().empty()) return;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    FAIL("the view never settled");
}

ModelSearchOutcome finished(ModelSearch& search)
{
    search.wait();
    std::optional<ModelSearchOutcome> outcome = search.take();
    REQUIRE(outcome);
    return *outcome;
}

/// A search's outcome, which must have found `k` models: names the error otherwise.
ModelSearchOutcome foundModels(ModelSearch& search, const EditingSession& session, const ModelSearchRequest& request)
{
    INFO(query::descriptorName(request.descriptor));
    REQUIRE(search.search(session, request));
    const ModelSearchOutcome found = finished(search);
    INFO(found.error);
    REQUIRE(found.results);
    REQUIRE(found.results->size() == request.k);
    return found;
}

/// The smooth unit sphere a voxel ball should find first, as a model file.
void writeRoundModel(const std::string& path)
{
    query::SyntheticShape round;
    round.family = "ellipsoid";
    round.proportions = {1.0, 1.0 / 0.7, 1.0 / 0.5};
    round.tessellation = 40;
    query::writeColouredPly(query::buildShape(round), path);
}

} // namespace

TEST_CASE("editor query: the sculpture finds the round model first, a box of nothing says so, a placed model is one edit that undoes", "[editor][query]")
{
    TempDir dir;
    for (const query::LabeledModel& m : query::syntheticSet(2, 31)) {
        std::filesystem::create_directories(dir.path() / "models" / m.label);
        query::writeColouredPly(query::buildShape(m.shape), (dir.path() / "models" / m.label / (m.name + ".ply")).string());
    }
    writeRoundModel(dir.file("models/round.ply"));
    REQUIRE(runCli(dir, "index add lib.vdblib models --recursive --no-render").exitCode == 0);
    REQUIRE(runCli(dir, "new ball.vdb --shape sphere --size 24").exitCode == 0);

    EditingSession session(dir.file("ball.vdb"), quietSession());
    settle(session);
    ModelSearch search;
    ModelSearchRequest request;
    request.library = dir.file("lib.vdblib");
    request.k = 3;
    for (const query::Descriptor d : {query::Descriptor::Combined, query::Descriptor::ClusterD2, query::Descriptor::D2}) {
        request.descriptor = d;
        const ModelSearchOutcome found = foundModels(search, session, request);
        // The voxel ball reads as the round model by every ranking (ClusterD2+Color's featureless
        // surface: samples spread evenly, not along the lattice's facets).
        CHECK((*found.results)[0].model.name == "round");
        CHECK((*found.results)[0].distance <= (*found.results)[1].distance);
        CHECK(found.results->front().thumbnail.width == 0); // added without the renderer: none
    }
    // A box around part of the ball searches with that part; one far from it finds nothing to search with.
    request.box = WorldBounds{Vec3d(0, -30, -30), Vec3d(30, 30, 30)};
    REQUIRE(search.search(session, request));
    CHECK(finished(search).results);
    request.box = WorldBounds{Vec3d(500, 500, 500), Vec3d(510, 510, 510)};
    REQUIRE(search.search(session, request));
    CHECK(finished(search).error.find("box") != std::string::npos);
    // A library that is not there: one line.
    request.library = dir.file("missing.vdblib");
    REQUIRE(search.search(session, request));
    CHECK(finished(search).error.find("does not exist") != std::string::npos);

    // The round model placed at a point beside the ball, a radius of 6: solid there, and Undo takes it away.
    const std::optional<SurfaceHit> hit = session.pick({60, 0, 0}, {-1, 0, 0});
    REQUIRE(hit);
    const std::array<double, 3> beside{hit->point[0] + 4.0, hit->point[1], hit->point[2]};
    session.autosave();
    const uint64_t before = session.scene().storedLevel0().stats().activeVoxels;
    REQUIRE(search.place(session, dir.file("models/round.ply"), beside, 6.0, ""));
    CHECK_FALSE(search.place(session, dir.file("models/round.ply"), beside, 6.0, "")); // one job at a time
    const ModelSearchOutcome placed = finished(search);
    INFO(placed.error);
    REQUIRE(placed.placement);
    Command c;
    c.kind = Command::Kind::ApplyOp;
    c.op = *placed.placement;
    session.apply(c);
    session.autosave();
    const Volume after = session.scene().storedLevel0();
    CHECK(after.stats().activeVoxels > before);
    // The unit sphere's box has a half diagonal of sqrt(3): scaled to 6, the sphere's radius is 6 / sqrt(3).
    CHECK(double(after.stats().bboxMax[0] + 1) * after.voxelSize() >= beside[0] + 6.0 / std::sqrt(3.0) - 1.0);
    Command undo;
    undo.kind = Command::Kind::Undo;
    session.apply(undo);
    session.autosave();
    CHECK(session.scene().storedLevel0().stats().activeVoxels == before);
    // A model that cannot be read: one line, nothing placed.
    std::ofstream(dir.file("broken.ply")) << "ply\nformat ascii 1.0\nelement vertex 99\nend_header\n1 2\n";
    REQUIRE(search.place(session, dir.file("broken.ply"), beside, 6.0, ""));
    const ModelSearchOutcome failed = finished(search);
    CHECK_FALSE(failed.placement);
    CHECK_FALSE(failed.error.empty());
}

#include "panels/QueryPanel.h"

#include <imgui.h>

TEST_CASE("editor query panel (render): the search ranks with the sculpture's light field, and Search and Place at the brush clicked through ImGui give one placing command", "[editor][query]")
{
    TempDir dir;
    for (const query::LabeledModel& m : query::syntheticSet(1, 5)) {
        std::filesystem::create_directories(dir.path() / "models" / m.label);
        query::writeColouredPly(query::buildShape(m.shape), (dir.path() / "models" / m.label / (m.name + ".ply")).string());
    }
    writeRoundModel(dir.file("models/round.ply"));
    REQUIRE(runCli(dir, "index add lib.vdblib models --recursive").exitCode == 0); // with light fields and thumbnails
    REQUIRE(runCli(dir, "new ball.vdb --shape sphere --size 24").exitCode == 0);
    EditingSession session(dir.file("ball.vdb"), quietSession());
    settle(session);
    SessionWorker worker(session);

    // The search draws the sculpture's silhouettes on its own thread and device: the voxel ball's light
    // field finds the round model first, alone and combined.
    {
        ModelSearch search;
        ModelSearchRequest request;
        request.library = dir.file("lib.vdblib");
        request.k = 3;
        request.lightField = true;
        for (const query::Descriptor d : {query::Descriptor::LightField, query::Descriptor::Combined}) {
            request.descriptor = d;
            const ModelSearchOutcome found = foundModels(search, session, request);
            CHECK(found.note.empty());
            CHECK((*found.results)[0].model.name == "round");
            CHECK((*found.results)[0].distance < (*found.results)[1].distance);
        }
        // Without the light field asked for, ranking by it is refused in one line.
        request.lightField = false;
        request.descriptor = query::Descriptor::LightField;
        REQUIRE(search.search(session, request));
        CHECK(finished(search).error.find("lightfield") != std::string::npos);
    }

    ImGuiContext* imgui = ImGui::CreateContext();
    ImGuiIO& io = ImGui::GetIO();
    io.IniFilename = nullptr;
    io.DisplaySize = ImVec2(600, 900);
    unsigned char* pixels = nullptr;
    int width = 0, height = 0;
    io.Fonts->GetTexDataAsRGBA32(&pixels, &width, &height);
    QueryPanel panel;
    panel.library = dir.file("lib.vdblib");
    panel.lightField = true;
    std::map<std::string, std::array<float, 4>> rects;
    std::vector<Command> issued;
    std::string status;
    const std::optional<std::array<double, 3>> brushAt = std::array<double, 3>{20, 0, 0};
    const auto frame = [&](std::optional<std::array<float, 4>> over, bool down) {
        io.DeltaTime = 1.0f / 60.0f;
        if (over) io.MousePos = ImVec2(0.5f * ((*over)[0] + (*over)[2]), 0.5f * ((*over)[1] + (*over)[3]));
        io.MouseDown[0] = down;
        ImGui::NewFrame();
        ImGui::SetNextWindowPos(ImVec2(0, 0));
        ImGui::SetNextWindowSize(ImVec2(600, 900));
        ImGui::Begin("Find models");
        panel.draw(worker, brushAt, issued, status, rects);
        ImGui::End();
        ImGui::Render();
    };
    const auto click = [&](const std::string& label) {
        INFO(label);
        REQUIRE(rects.count(label) == 1);
        const auto at = rects.at(label);
        frame(at, false);
        frame(at, true);
        frame(at, false);
    };
    frame(std::nullopt, false);
    click("Search");
    panel.search().wait();
    frame(std::nullopt, false); // the results come in
    INFO(status);
    REQUIRE(panel.results().size() == 7);
    CHECK(status.find("without the light field") == std::string::npos);
    for (const ModelSearchResult& r : panel.results()) CHECK(r.thumbnail.width == 128); // drawn as cells
    frame(std::nullopt, false); // the result rows are laid out
    REQUIRE(issued.empty());
    click("Place 1");
    panel.search().wait();
    frame(std::nullopt, false); // the placing comes in
    REQUIRE(issued.size() == 1);
    CHECK(issued[0].kind == Command::Kind::ApplyOp);
    CHECK(std::filesystem::exists(issued[0].op.at("brush").at("file").get<std::string>()));
    CHECK(status.find("placed") != std::string::npos);
    ImGui::DestroyContext(imgui);
    worker.submit(issued[0]);
    worker.waitIdle();
    CHECK(session.history().undoDepth() == 1);
}
