// Everything a user does in the editor, as plain commands: front ends (the desktop window, the headset)
// only turn device input into these, and a recorded session is the list of them with their frames, so
// it replays headless, bit for bit.
#pragma once

#include "editor/BrushSettings.h"
#include "editor/Ray.h"
#include "render/RenderTypes.h"

#include <nlohmann/json.hpp>

#include <array>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace vdbclay {

/// A malformed session file or command; what() names the place ("commands[3].point: ...").
class SessionError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

struct Command {
    enum class Kind {
        StrokeBegin, // along `ray` (the pointer's) or at `point` (the surface under it) with `pressure`
        StrokeMove,  // the pointer moved along `ray` or to `point` with `pressure` (a move brush: the drag's point)
        StrokeEnd,
        SetBrush,    // `brush`
        Undo,
        Redo,
        Save,        // to `path`, or the scene's own file when empty
        SetCamera,   // `camera`
        DefineMaterial, // `material`: a script's material definition (name, color, toughness, texture)
        ApplyOp,     // `op`: one stroke-script op as one edit (tool stamps, imported meshes)
    };
    Kind kind = Kind::StrokeEnd;
    /// Strokes: where the brush went. A front end gives the pointer's `ray` and the session places the
    /// brush on the surface as the stroke began; the record then holds both, with the surface's outward
    /// `normal` there (what sinks an add stamp so that it raises the surface by strength x radius).
    /// A point alone (a headset's brush at the hand, older sessions, tests) is taken as it is.
    std::optional<std::array<double, 3>> point;
    std::optional<Ray> ray;
    std::optional<std::array<double, 3>> normal;
    double pressure = 1.0;
    /// StrokeMove: the stamps this point adds go with those of the next point, as one op (the edit
    /// worker merges pending points of a stroke so that a slow brush keeps up; a grab applies only the
    /// last drag). Recorded ("merged": true), so a replay merges the same.
    bool mergedWithNext = false;
    std::optional<BrushSettings> brush; // SetBrush only: a session holds many commands, few of them brushes
    render::Camera camera;
    std::string path;
    nlohmann::json material;
    nlohmann::json op;
};

const char* commandName(Command::Kind kind);
nlohmann::json commandJson(const Command& command);
/// Throws SessionError naming `where` and the key.
Command parseCommand(const nlohmann::json& json, const std::string& where);

/// A command as a session file lists it: the frame it was applied before, and the session's clock then.
struct RecordedCommand {
    uint64_t frame = 0;
    double time = 0.0;
    Command command;
};

struct SessionRecord {
    std::array<int, 2> viewport{1280, 720}; // the window's size when recording began
    std::vector<RecordedCommand> commands;
    uint64_t frames = 0; // frames the session ran
};

/// Hands `apply` the recorded commands from index `next` on that belong before frame `frame`, save
/// commands skipped (a replay never writes the files the recorded session saved to); returns the next
/// index and, in `time`, the clock of the last one.
std::size_t forRecordedFrame(const SessionRecord& record, std::size_t next, uint64_t frame, double* time,
                             const std::function<void(const Command&)>& apply);

nlohmann::json sessionRecordJson(const SessionRecord& record);
/// Reads a session file; throws SessionError for unreadable or malformed ones.
SessionRecord loadSessionRecord(const std::string& path);
/// The same from the file's text; `name` labels the errors.
SessionRecord parseSessionRecord(const std::string& text, const std::string& name);
/// Writes the record atomically (a crash leaves the old file or the new one).
void saveSessionRecord(const SessionRecord& record, const std::string& path);

} // namespace vdbclay
