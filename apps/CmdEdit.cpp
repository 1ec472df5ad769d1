// vdbclay edit: the editor. Opens a scene in a window (GLFW + Dear ImGui) or, with --headless, replays
// a recorded session with no window, then saves, draws or exports what it made.
#include "Cli.h"

#include "desktop/DesktopEditor.h"
#include "desktop/DesktopSettings.h"
#include "editor/EditedScene.h"
#include "editor/EditingSession.h"
#include "render/ImageFile.h"
#include "render/ScenePicture.h"
#include "render/VulkanContext.h"
#include "scene/SceneStore.h"
#include "vdb_hermite/AtomicFile.h"
#include "vr/VrEditor.h"

#include <CLI/CLI.hpp>

#include <cstdlib>
#include <filesystem>
#include <iostream>

namespace vdbclay::cli {

CLI::App* addEditCommand(CLI::App& parent, EditOptions& o)
{
    CLI::App* cmd = parent.add_subcommand("edit", "Sculpt a scene interactively (a window), or replay a recorded session (--headless)");
    cmd->add_option("scene", o.scene, "Scene: a .vdb (edited through SCENE.vdb.edit.vdbclay beside it) or a store (.vdbclay)")
        ->required()->type_name("SCENE")->check(sceneInput());
    cmd->add_option("--memory-budget", o.memoryBudgetMB, "Resident bricks and their meshes may take at most this many MB")
        ->capture_default_str()->type_name("MB")->check(memoryBudget());
    cmd->add_option("--record", o.record, "Write every command with its frame and time (rewritten at each autosave)")->type_name("SESSION.json");
    cmd->add_option("--replay", o.replay, "Apply a recorded session")->type_name("SESSION.json");
    cmd->add_flag("--headless", o.headless, "No window: replay, then save (-o), draw (--screenshot) or export (--export-script)");
    cmd->add_option("--frames", o.frames, "Headless: replay only the session's first N frames; --vr: end the session after N frames")
        ->type_name("N")->check(unsignedInteger());
    cmd->add_flag("--vr", o.vr, "Sculpt in a headset through OpenXR (the active runtime, or XR_RUNTIME_JSON's): the dominant hand "
                                "sculpts (trigger: pressure; thumbstick: size, modes; A/B: undo, redo), the other grabs the "
                                "world (both: turn and scale; thumbstick: fly; X: frame the scene again)");
    cmd->add_option("--hand", o.hand, "--vr: the hand that sculpts")->capture_default_str()->check(CLI::IsMember({"left", "right"}));
    cmd->add_option("--screenshot", o.screenshot, "Headless: draw the view after the replay into a PNG (needs a Vulkan device)")->type_name("OUT.png");
    cmd->add_option("--size", o.size, "The screenshot's size (default: the session's window size)")->type_name("WxH");
    cmd->add_option("-o,--output", o.output, "Headless: save the result here (.vdb or .vdbclay). A replay never writes a .vdb scene itself; a store takes the edits, as in any session")
        ->type_name("OUT");
    cmd->add_option("--export-script", o.exportScript, "Headless: write the ops in effect (undone strokes left out) as a stroke script (for 'vdbclay sculpt')")
        ->type_name("OUT.json");
    cmd->add_flag("--discard-recovery", o.discardRecovery, "A .vdb: drop edits autosaved after its last save instead of recovering them");
    cmd->add_option("--autosave", o.autosaveSeconds, "Seconds between autosaves while sculpting")->capture_default_str()->type_name("S")->check(positiveNumber());
    cmd->add_flag("--json", o.json, "Headless: print {\"recovered_edits\", \"frames\", \"commands\", \"stamps\", \"undo_depth\", ...}; "
                                    "--vr: {\"frames\", \"missed_frames\", \"frame_ms\", \"states\", ...}");
    cmd->footer(desktopShortcutsHelp(loadKeymap(defaultConfigFolder(), false, nullptr)));
    return cmd;
}

namespace {

/// Every file the editor writes goes through the check all commands make, before any work: never one of
/// its inputs (the scene, its working store, the session replayed; through links), the extension names
/// the kind, an existing file of another kind is never replaced, and no two outputs name one file. A
/// replay never writes the scene's own file, however it is spelled.
void checkEditOutputs(const EditOptions& o)
{
    std::vector<std::string> inputs{o.scene, o.replay};
    if (!isStorePath(o.scene)) inputs.push_back(workingStorePath(o.scene));
    if (!o.output.empty()) {
        requireSceneExtension(o.output);
        checkOutput(o.output, isStorePath(o.output) ? OutputForm::Store : OutputForm::NativeVolume, inputs);
    }
    if (!o.screenshot.empty()) checkOutput(o.screenshot, OutputForm::Png, inputs);
    if (!o.exportScript.empty()) checkOutput(o.exportScript, OutputForm::Json, inputs);
    if (!o.record.empty()) checkOutput(o.record, OutputForm::Json, inputs);
    checkDistinctOutputs({{"-o", o.output}, {"--screenshot", o.screenshot}, {"--export-script", o.exportScript}, {"--record", o.record}});
}

} // namespace

int runEdit(const EditOptions& o)
{
    checkEditOutputs(o);
    if (o.vr && (o.headless || !o.replay.empty()))
        throw UsageError("--vr runs a live session: replay its record with --replay SESSION.json --headless");
    if (!o.headless && (!o.output.empty() || !o.screenshot.empty() || !o.exportScript.empty() || (o.frames && !o.vr)))
        throw UsageError("-o, --screenshot and --export-script go with --headless, --frames with --headless or --vr");
    if (!o.size.empty() && o.screenshot.empty()) throw UsageError("--size goes with --screenshot");
    std::optional<std::pair<int, int>> size;
    if (!o.size.empty()) size = parsePictureSize(o.size, "--size");
    std::optional<SessionRecord> replay;
    if (!o.replay.empty()) replay = loadSessionRecord(o.replay);
    if (!o.headless && !o.vr && !desktopAvailable()) {
        printError("no display to open the editor's window on (DISPLAY and WAYLAND_DISPLAY are unset): draw pictures with "
                   "'vdbclay render', or replay a session with 'vdbclay edit SCENE --replay SESSION.json --headless'");
        return kExitFailure;
    }

    SessionOptions options;
    options.memoryBudgetBytes = uint64_t(o.memoryBudgetMB * 1048576.0);
    options.recordPath = o.record;
    options.discardRecovery = o.discardRecovery;
    // A headless replay is a reproducible run: it starts from the scene as saved, and what it does to a
    // .vdb's working store is dropped at the end (it never writes the .vdb; -o keeps its result).
    const bool replayOnly = o.headless && !o.replay.empty();
    options.refuseUnsaved = replayOnly;
    options.autosaveSeconds = o.autosaveSeconds;
    options.message = [](const std::string& text) { std::cerr << "vdbclay: " << text << "\n"; };
    std::unique_ptr<EditingSession> session;
    try {
        session = std::make_unique<EditingSession>(o.scene, options);
    } catch (const std::invalid_argument& e) {
        throw UsageError(e.what()); // a budget too small for one brick, discarding a store's edits
    }
    if (session->recoveredEdits() > 0)
        std::cerr << "vdbclay: recovered " << session->recoveredEdits() << (session->recoveredEdits() == 1 ? " edit" : " edits")
                  << " autosaved after the last save of '" << o.scene
                  << "' (kept: save to keep them for good" << (isStorePath(o.scene) ? "" : ", or run again with --discard-recovery to drop them")
                  << ")\n";

    if (o.vr) {
        vr::VrOptions vrOptions;
        vrOptions.frames = o.frames;
        vrOptions.dominantHand = o.hand == "left" ? 0 : 1;
        vrOptions.json = o.json;
        return vr::runVrEditor(std::move(session), vrOptions);
    }
    if (!o.headless) return runDesktopEditor(options, std::move(session), replay ? &*replay : nullptr);

    // Whatever way the run ends, a replay's edits leave the .vdb's working store with the session.
    struct DropReplayEdits {
        std::unique_ptr<EditingSession>& session;
        const std::string& scene;
        bool enabled;
        ~DropReplayEdits()
        {
            if (!enabled) return;
            session.reset(); // its last autosave first
            try {
                dropUnsavedWorkingStore(scene);
            } catch (const std::exception& e) {
                printError(std::string("could not drop the replay's edits from the working store: ") + e.what());
            }
        }
    } dropReplayEdits{session, o.scene, replayOnly && !isStorePath(o.scene)};

    const auto start = std::chrono::steady_clock::now();
    uint64_t frames = 0;
    FrameReport last;
    if (replay) replaySession(*session, *replay, o.frames, [&](uint64_t, const FrameReport& r) {
        ++frames;
        last = r;
    });
    if (!o.exportScript.empty()) {
        const std::string text = session->appliedScript().dump(1) + "\n";
        writeFileAtomically(o.exportScript, [&](std::ostream& out) { out << text; });
    }
    if (!o.output.empty()) {
        Command save;
        save.kind = Command::Kind::Save;
        save.path = o.output;
        session->apply(save);
    }
    if (!o.screenshot.empty()) {
        std::unique_ptr<render::VulkanContext> context;
        try {
            context = std::make_unique<render::VulkanContext>();
        } catch (const render::NoVulkanDevice& e) {
            printError(std::string("cannot draw the screenshot: ") + e.what());
            return kExitFailure;
        }
        const std::array<int, 2> viewport = replay ? replay->viewport : std::array<int, 2>{1280, 720};
        render::PictureRequest request;
        request.width = size ? size->first : viewport[0];
        request.height = size ? size->second : viewport[1];
        request.textureFolder = std::filesystem::path(o.scene).parent_path().string();
        session->frame(0.0, {request.width, request.height});
        session->scene().waitForLoads();
        session->frame(0.0, {request.width, request.height});
        const render::Picture picture = render::renderStreamed(*context, session->scene(), session->camera(), request);
        render::writePng(picture.image, o.screenshot);
    }
    if (o.json) {
        printJson({{"scene", o.scene},
                   {"recovered_edits", session->recoveredEdits()},
                   {"frames", frames},
                   {"commands", replay ? replay->commands.size() : 0},
                   {"stamps", session->stats().stampsApplied},
                   {"refused", session->stats().opsRefused},
                   {"undo_depth", session->history().undoDepth()},
                   {"redo_depth", session->history().redoDepth()},
                   {"edits", session->scene().edits()},
                   {"resident_bytes", last.residentBytes},
                   {"seconds", secondsSince(start)}});
    } else {
        std::cout << "replayed " << frames << " frames (" << session->stats().stampsApplied << " stamps) on " << o.scene << "\n";
    }
    return kExitOk;
}

} // namespace vdbclay::cli
