#include "editor/SessionCommand.h"

#include "sculpt/StrokeScript.h"

#include "vdb_hermite/AtomicFile.h"
#include "vdb_hermite/FileStatus.h"
#include "vdb_hermite/PrintableText.h"
#include "vdb_hermite/StrictJson.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

namespace vdbclay {

namespace {

struct KindName {
    Command::Kind kind;
    const char* name;
};
constexpr KindName kKinds[] = {
    {Command::Kind::StrokeBegin, "stroke_begin"}, {Command::Kind::StrokeMove, "stroke_move"},
    {Command::Kind::StrokeEnd, "stroke_end"},     {Command::Kind::SetBrush, "brush"},
    {Command::Kind::Undo, "undo"},                {Command::Kind::Redo, "redo"},
    {Command::Kind::Save, "save"},                {Command::Kind::SetCamera, "camera"},
    {Command::Kind::DefineMaterial, "material"}, {Command::Kind::ApplyOp, "op"},
};

constexpr uint64_t kMaxSessionBytes = 256ull << 20;

[[noreturn]] void fail(const std::string& where, const std::string& message) { throw SessionError(where + ": " + message); }

std::array<double, 3> vec3(const nlohmann::json& json, const std::string& where)
{
    if (!json.is_array() || json.size() != 3) fail(where, "must be [x, y, z]");
    std::array<double, 3> v{};
    for (std::size_t i = 0; i < 3; ++i) {
        if (!json[i].is_number() || !std::isfinite(json[i].get<double>())) fail(where, "must hold three finite numbers");
        v[i] = json[i].get<double>();
    }
    return v;
}

double finite(const nlohmann::json& json, const std::string& where)
{
    if (!json.is_number() || !std::isfinite(json.get<double>())) fail(where, "must be a finite number");
    return json.get<double>();
}

const nlohmann::json& required(const nlohmann::json& json, const char* key, const std::string& where)
{
    if (!json.contains(key)) fail(where + "." + key, "missing");
    return json.at(key);
}

/// A material or op is checked as a stroke script would check it, so that a session is refused whole,
/// naming the command, before any of it is applied. `part` is "materials" or "ops".
void checkAsScript(const char* part, const nlohmann::json& value, const std::string& where)
{
    nlohmann::json script{{"ops", nlohmann::json::array()}};
    script[part] = nlohmann::json::array({value});
    try {
        (void)parseStrokeScript(script.dump());
    } catch (const ScriptError& e) {
        // "materials[0].color: must be ..." -> "WHERE.color: must be ..."
        const std::string message = e.what(), prefix = std::string(part) + "[0]";
        if (message.rfind(prefix, 0) == 0) throw SessionError(where + message.substr(prefix.size()));
        fail(where, message);
    }
}

} // namespace

const char* commandName(Command::Kind kind)
{
    for (const KindName& k : kKinds)
        if (k.kind == kind) return k.name;
    return "?";
}

nlohmann::json commandJson(const Command& c)
{
    nlohmann::json j = {{"command", commandName(c.kind)}};
    switch (c.kind) {
    case Command::Kind::StrokeBegin:
    case Command::Kind::StrokeMove:
        if (c.point) j["point"] = *c.point;
        if (c.normal) j["normal"] = *c.normal;
        if (c.ray) j["ray"] = {{"origin", c.ray->origin}, {"direction", c.ray->direction}};
        j["pressure"] = c.pressure;
        if (c.mergedWithNext) j["merged"] = true;
        break;
    case Command::Kind::SetBrush: j["brush"] = brushSettingsJson(c.brush.value_or(BrushSettings{})); break;
    case Command::Kind::Save:
        if (!c.path.empty()) j["path"] = c.path;
        break;
    case Command::Kind::SetCamera:
        j["eye"] = c.camera.eye;
        j["target"] = c.camera.target;
        j["up"] = c.camera.up;
        j["fov"] = c.camera.fovYDegrees;
        break;
    case Command::Kind::DefineMaterial: j["material"] = c.material; break;
    case Command::Kind::ApplyOp: j["op"] = c.op; break;
    default: break;
    }
    return j;
}

Command parseCommand(const nlohmann::json& j, const std::string& where)
{
    if (!j.is_object()) fail(where, "must be an object");
    const nlohmann::json& name = required(j, "command", where);
    Command c;
    bool known = false;
    for (const KindName& k : kKinds)
        if (name.is_string() && name.get<std::string>() == k.name) {
            c.kind = k.kind;
            known = true;
        }
    if (!known) fail(where + ".command", "unknown command (stroke_begin, stroke_move, stroke_end, brush, undo, redo, save, camera, material or op)");
    // The keys a command may have (no allocation: a session may hold hundreds of thousands of commands).
    std::array<const char*, 8> keys{"command", "frame", "time"};
    std::size_t keyCount = 3;
    const auto allow = [&](std::initializer_list<const char*> more) {
        for (const char* k : more) keys[keyCount++] = k;
    };
    switch (c.kind) {
    case Command::Kind::StrokeBegin:
    case Command::Kind::StrokeMove:
        if (!j.contains("ray")) c.point = vec3(required(j, "point", where), where + ".point");
        else {
            const nlohmann::json& ray = j.at("ray");
            if (!ray.is_object() || ray.size() != 2 || !ray.contains("origin") || !ray.contains("direction"))
                fail(where + ".ray", "must be an object {\"origin\": [x, y, z], \"direction\": [x, y, z]}");
            Ray r{vec3(ray.at("origin"), where + ".ray.origin"), vec3(ray.at("direction"), where + ".ray.direction")};
            const double length = std::sqrt(r.direction[0] * r.direction[0] + r.direction[1] * r.direction[1] + r.direction[2] * r.direction[2]);
            if (!(length > 1e-12) || !std::isfinite(length)) fail(where + ".ray.direction", "must be a non-zero direction");
            c.ray = r;
            if (j.contains("point")) c.point = vec3(j.at("point"), where + ".point");
        }
        if (j.contains("normal")) c.normal = vec3(j.at("normal"), where + ".normal");
        if (j.contains("pressure")) c.pressure = finite(j.at("pressure"), where + ".pressure");
        if (!(c.pressure > 0.0 && c.pressure <= 1.0)) fail(where + ".pressure", "must be in (0, 1]");
        if (j.contains("merged")) {
            if (!j.at("merged").is_boolean()) fail(where + ".merged", "must be true or false");
            if (c.kind != Command::Kind::StrokeMove) fail(where + ".merged", "belongs to stroke moves");
            c.mergedWithNext = j.at("merged").get<bool>();
        }
        allow({"point", "pressure", "ray", "normal", "merged"});
        break;
    case Command::Kind::SetBrush:
        try {
            c.brush = parseBrushSettings(required(j, "brush", where));
        } catch (const std::invalid_argument& e) {
            fail(where, e.what());
        }
        allow({"brush"});
        break;
    case Command::Kind::Save:
        if (j.contains("path")) {
            if (!j.at("path").is_string() || j.at("path").get<std::string>().empty()) fail(where + ".path", "must be a file name");
            c.path = j.at("path").get<std::string>();
        }
        allow({"path"});
        break;
    case Command::Kind::SetCamera:
        c.camera.eye = vec3(required(j, "eye", where), where + ".eye");
        c.camera.target = vec3(required(j, "target", where), where + ".target");
        if (j.contains("up")) c.camera.up = vec3(j.at("up"), where + ".up");
        if (c.camera.up == std::array<double, 3>{0.0, 0.0, 0.0}) fail(where + ".up", "must not be [0, 0, 0]");
        if (j.contains("fov")) c.camera.fovYDegrees = finite(j.at("fov"), where + ".fov");
        if (!(c.camera.fovYDegrees > 1.0 && c.camera.fovYDegrees < 179.0)) fail(where + ".fov", "must be between 1 and 179 degrees");
        if (c.camera.eye == c.camera.target) fail(where, "the eye and the target must differ");
        allow({"eye", "target", "up", "fov"});
        break;
    case Command::Kind::DefineMaterial:
        c.material = required(j, "material", where);
        if (!c.material.is_object()) fail(where + ".material", "must be a material object");
        checkAsScript("materials", c.material, where + ".material");
        allow({"material"});
        break;
    case Command::Kind::ApplyOp:
        c.op = required(j, "op", where);
        if (!c.op.is_object()) fail(where + ".op", "must be a stroke-script op");
        checkAsScript("ops", c.op, where + ".op");
        allow({"op"});
        break;
    default: break;
    }
    for (const auto& item : j.items())
        if (std::none_of(keys.begin(), keys.begin() + std::ptrdiff_t(keyCount), [&](const char* k) { return item.key() == k; })) fail(where + "." + printableText(item.key(), 80), "unknown key");
    return c;
}

nlohmann::json sessionRecordJson(const SessionRecord& record)
{
    nlohmann::json commands = nlohmann::json::array();
    for (const RecordedCommand& rc : record.commands) {
        nlohmann::json j = commandJson(rc.command);
        j["frame"] = rc.frame;
        j["time"] = rc.time;
        commands.push_back(std::move(j));
    }
    return {{"vdbclay_session", 1}, {"viewport", record.viewport}, {"frames", record.frames}, {"commands", std::move(commands)}};
}

std::size_t forRecordedFrame(const SessionRecord& record, std::size_t next, uint64_t frame, double* time,
                             const std::function<void(const Command&)>& apply)
{
    while (next < record.commands.size() && record.commands[next].frame <= frame) {
        const RecordedCommand& rc = record.commands[next++];
        if (time) *time = rc.time;
        if (rc.command.kind != Command::Kind::Save) apply(rc.command);
    }
    return next;
}

SessionRecord loadSessionRecord(const std::string& path)
{
    // Checked before reading: /dev/zero or a FIFO would be read without end.
    if (const auto why = unreadableAsFile(path, kMaxSessionBytes)) throw SessionError("session file: " + printableText(*why, 400));
    std::ifstream in(path, std::ios::binary);
    if (!in) throw SessionError("cannot read the session file '" + printableText(path, 200) + "'");
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) throw SessionError("cannot read the session file '" + printableText(path, 200) + "'");
    return parseSessionRecord(text.str(), path);
}

SessionRecord parseSessionRecord(const std::string& text, const std::string& name)
{
    const std::string where = "'" + printableText(name, 200) + "'";
    nlohmann::json root;
    try {
        root = parseStrictJson(text, where);
    } catch (const std::invalid_argument& e) {
        throw SessionError(e.what());
    }
    if (!root.is_object() || !root.contains("vdbclay_session")) fail(where, "not a VDBClay session file (no \"vdbclay_session\" key)");
    if (root.at("vdbclay_session") != 1) fail(where + ".vdbclay_session", "this version reads sessions of version 1");
    for (const auto& item : root.items())
        if (item.key() != "vdbclay_session" && item.key() != "viewport" && item.key() != "frames" && item.key() != "commands")
            fail(where + "." + printableText(item.key(), 80), "unknown key");
    SessionRecord record;
    if (root.contains("viewport")) {
        const nlohmann::json& v = root.at("viewport");
        if (!v.is_array() || v.size() != 2 || !v[0].is_number_integer() || !v[1].is_number_integer() || v[0] < 1 || v[1] < 1 ||
            v[0] > render::kMaxViewportSide || v[1] > render::kMaxViewportSide)
            fail(where + ".viewport", "must be [width, height] in pixels, 1 to " + std::to_string(render::kMaxViewportSide));
        record.viewport = {v[0].get<int>(), v[1].get<int>()};
    }
    const nlohmann::json& commands = required(root, "commands", where);
    if (!commands.is_array()) fail(where + ".commands", "must be an array");
    uint64_t lastFrame = 0;
    record.commands.reserve(commands.size()); // a command is large: growing the list would copy each many times
    for (std::size_t i = 0; i < commands.size(); ++i) {
        const std::string at = where + ".commands[" + std::to_string(i) + "]";
        RecordedCommand rc;
        rc.command = parseCommand(commands[i], at);
        const nlohmann::json& frame = required(commands[i], "frame", at);
        if (!frame.is_number_unsigned() || frame.get<uint64_t>() > (uint64_t(1) << 40)) fail(at + ".frame", "must be a frame number");
        rc.frame = frame.get<uint64_t>();
        if (rc.frame < lastFrame) fail(at + ".frame", "frames must not go back");
        lastFrame = rc.frame;
        if (commands[i].contains("time")) rc.time = finite(commands[i].at("time"), at + ".time");
        record.commands.push_back(std::move(rc));
    }
    record.frames = lastFrame + 1;
    if (root.contains("frames")) {
        const nlohmann::json& f = root.at("frames");
        if (!f.is_number_unsigned() || f.get<uint64_t>() > (uint64_t(1) << 40)) fail(where + ".frames", "must be a frame count");
        record.frames = std::max(record.frames, f.get<uint64_t>());
    }
    return record;
}

void saveSessionRecord(const SessionRecord& record, const std::string& path)
{
    const std::string text = sessionRecordJson(record).dump(1) + "\n";
    writeFileAtomically(path, [&](std::ostream& out) { out << text; });
}

} // namespace vdbclay
