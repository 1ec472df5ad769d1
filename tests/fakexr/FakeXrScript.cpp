#include "FakeXrScript.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace fakexr {

XrVector3f rotate(const XrQuaternionf& q, const XrVector3f& v)
{
    // v + 2 w (u x v) + 2 u x (u x v), u the quaternion's vector part.
    const float ux = q.x, uy = q.y, uz = q.z, w = q.w;
    const float cx = uy * v.z - uz * v.y, cy = uz * v.x - ux * v.z, cz = ux * v.y - uy * v.x;
    const float dx = uy * cz - uz * cy, dy = uz * cx - ux * cz, dz = ux * cy - uy * cx;
    return {v.x + 2 * (w * cx + dx), v.y + 2 * (w * cy + dy), v.z + 2 * (w * cz + dz)};
}

namespace {

XrQuaternionf product(const XrQuaternionf& a, const XrQuaternionf& b)
{
    return {a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
            a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
}

XrQuaternionf normalized(XrQuaternionf q)
{
    const float n = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
    if (!(n > 0.0f)) return {0, 0, 0, 1};
    return {q.x / n, q.y / n, q.z / n, q.w / n};
}

XrPosef interpolate(const XrPosef& a, const XrPosef& b, float t)
{
    XrQuaternionf qb = b.orientation;
    const float dot = a.orientation.x * qb.x + a.orientation.y * qb.y + a.orientation.z * qb.z + a.orientation.w * qb.w;
    if (dot < 0) qb = {-qb.x, -qb.y, -qb.z, -qb.w};
    XrPosef p;
    p.orientation = normalized({a.orientation.x + t * (qb.x - a.orientation.x), a.orientation.y + t * (qb.y - a.orientation.y),
                                a.orientation.z + t * (qb.z - a.orientation.z), a.orientation.w + t * (qb.w - a.orientation.w)});
    p.position = {a.position.x + t * (b.position.x - a.position.x), a.position.y + t * (b.position.y - a.position.y),
                  a.position.z + t * (b.position.z - a.position.z)};
    return p;
}

/// The keys around `frame` and how far between them it lies.
template <typename Key>
void bracket(const std::vector<Key>& keys, uint64_t frame, const Key** a, const Key** b, float* t)
{
    auto after = std::upper_bound(keys.begin(), keys.end(), frame, [](uint64_t f, const Key& k) { return f < k.frame; });
    if (after == keys.begin()) {
        *a = *b = &keys.front();
        *t = 0;
    } else if (after == keys.end()) {
        *a = *b = &keys.back();
        *t = 0;
    } else {
        *a = &*(after - 1);
        *b = &*after;
        *t = float(double(frame - (*a)->frame) / double((*b)->frame - (*a)->frame));
    }
}

using nlohmann::json;

[[noreturn]] void bad(const std::string& where, const std::string& what)
{
    throw std::runtime_error("fakexr script: " + where + ": " + what);
}

XrPosef readPose(const json& j, const std::string& where, XrPosef pose)
{
    if (j.contains("position")) {
        const auto& p = j.at("position");
        if (!p.is_array() || p.size() != 3) bad(where + ".position", "expected [x, y, z]");
        pose.position = {p[0].get<float>(), p[1].get<float>(), p[2].get<float>()};
    }
    if (j.contains("orientation")) {
        const auto& q = j.at("orientation");
        if (!q.is_array() || q.size() != 4) bad(where + ".orientation", "expected [x, y, z, w]");
        pose.orientation = normalized({q[0].get<float>(), q[1].get<float>(), q[2].get<float>(), q[3].get<float>()});
    }
    return pose;
}

} // namespace

XrPosef multiply(const XrPosef& a, const XrPosef& b)
{
    XrPosef r;
    r.orientation = normalized(product(a.orientation, b.orientation));
    const XrVector3f t = rotate(a.orientation, b.position);
    r.position = {a.position.x + t.x, a.position.y + t.y, a.position.z + t.z};
    return r;
}

XrPosef inverse(const XrPosef& p)
{
    XrPosef r;
    r.orientation = {-p.orientation.x, -p.orientation.y, -p.orientation.z, p.orientation.w};
    const XrVector3f t = rotate(r.orientation, p.position);
    r.position = {-t.x, -t.y, -t.z};
    return r;
}

XrPosef HeadsetScript::headAt(uint64_t frame) const
{
    if (head.empty()) return HeadKey().pose;
    const HeadKey *a, *b;
    float t;
    bracket(head, frame, &a, &b, &t);
    return interpolate(a->pose, b->pose, t);
}

HandState HeadsetScript::handAt(int hand, uint64_t frame) const
{
    const auto& keys = hands[std::size_t(hand)];
    if (keys.empty()) {
        HandState s;
        s.pose.position = {hand == 0 ? -0.2f : 0.2f, 1.3f, -0.3f};
        return s;
    }
    const HandKey *a, *b;
    float t;
    bracket(keys, frame, &a, &b, &t);
    HandState s = a->state; // buttons step
    s.pose = interpolate(a->state.pose, b->state.pose, t);
    s.trigger = a->state.trigger + t * (b->state.trigger - a->state.trigger);
    s.squeeze = a->state.squeeze + t * (b->state.squeeze - a->state.squeeze);
    s.thumbstick = {a->state.thumbstick.x + t * (b->state.thumbstick.x - a->state.thumbstick.x),
                    a->state.thumbstick.y + t * (b->state.thumbstick.y - a->state.thumbstick.y)};
    return s;
}

HeadsetScript parseHeadsetScript(const std::string& text)
{
    json j;
    try {
        j = json::parse(text);
    } catch (const std::exception& e) {
        bad("(file)", e.what());
    }
    HeadsetScript s;
    try {
        s.stopAfterFrames = j.value("stop_after_frames", uint64_t(0));
        s.pace = j.value("pace", true);
        s.refreshHz = j.value("refresh_hz", 90.0);
        s.ipd = j.value("ipd", 0.064);
        s.width = j.value("width", 256);
        s.height = j.value("height", 256);
        if (j.contains("fov")) {
            const auto& f = j.at("fov");
            s.fov = {f.at("left").get<float>(), f.at("right").get<float>(), f.at("up").get<float>(), f.at("down").get<float>()};
        }
        if (j.contains("formats")) s.formats = j.at("formats").get<std::vector<int64_t>>();
        s.depthExtension = j.value("depth_extension", true);
        s.stereo = j.value("stereo", true);
        s.profile = j.value("profile", s.profile);
        if (j.contains("focus_lost_at")) s.focusLostAt = j.at("focus_lost_at").get<uint64_t>();
        if (j.contains("focus_back_at")) s.focusBackAt = j.at("focus_back_at").get<uint64_t>();
        if (j.contains("loss_pending_at")) s.lossPendingAt = j.at("loss_pending_at").get<uint64_t>();
        if (j.contains("capture")) {
            for (uint64_t f : j.at("capture").get<std::vector<uint64_t>>()) s.capture.insert(f);
        }
        if (j.contains("head")) {
            XrPosef last = HeadsetScript::HeadKey().pose;
            for (std::size_t i = 0; i < j.at("head").size(); ++i) {
                const auto& k = j.at("head")[i];
                HeadsetScript::HeadKey key;
                key.frame = k.at("frame").get<uint64_t>();
                key.pose = last = readPose(k, "head[" + std::to_string(i) + "]", last);
                if (!s.head.empty() && key.frame <= s.head.back().frame) bad("head[" + std::to_string(i) + "]", "frames must increase");
                s.head.push_back(key);
            }
        }
        const char* names[2] = {"left", "right"};
        for (int h = 0; h < 2; ++h) {
            if (!j.contains(names[h])) continue;
            HandState last;
            last.pose.position = {h == 0 ? -0.2f : 0.2f, 1.3f, -0.3f};
            const auto& keys = j.at(names[h]);
            for (std::size_t i = 0; i < keys.size(); ++i) {
                const auto& k = keys[i];
                const std::string where = std::string(names[h]) + "[" + std::to_string(i) + "]";
                HeadsetScript::HandKey key;
                key.frame = k.at("frame").get<uint64_t>();
                key.state = last;
                key.state.pose = readPose(k, where, last.pose);
                key.state.trigger = k.value("trigger", last.trigger);
                key.state.squeeze = k.value("squeeze", last.squeeze);
                if (k.contains("thumbstick")) {
                    const auto& t = k.at("thumbstick");
                    key.state.thumbstick = {t.at(0).get<float>(), t.at(1).get<float>()};
                }
                if (k.contains("buttons")) {
                    for (const auto& [name, down] : k.at("buttons").items()) key.state.buttons[name] = down.get<bool>();
                }
                if (!s.hands[h].empty() && key.frame <= s.hands[h].back().frame) bad(where, "frames must increase");
                s.hands[h].push_back(key);
                last = key.state;
            }
        }
    } catch (const json::exception& e) {
        bad("(keys)", e.what());
    }
    return s;
}

HeadsetScript loadHeadsetScript(const std::string& path)
{
    std::ifstream in(path);
    if (!in) throw std::runtime_error("fakexr script: cannot read " + path);
    std::stringstream text;
    text << in.rdbuf();
    return parseHeadsetScript(text.str());
}

} // namespace fakexr
