#include "vr/XrControllers.h"

#include <cstring>
#include <utility>
#include <vector>

namespace vdbclay::vr {

namespace {

XrPath path(XrInstance instance, const std::string& text)
{
    XrPath p = XR_NULL_PATH;
    check(xrStringToPath(instance, text.c_str(), &p), "xrStringToPath", instance);
    return p;
}

} // namespace

Pose poseOf(const XrPosef& p)
{
    Pose out;
    out.orientation = glm::dquat(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z);
    out.position = glm::dvec3(p.position.x, p.position.y, p.position.z);
    return out;
}

XrControllers::XrControllers(XrInstance instance, XrSession session) : instance_(instance), session_(session)
{
    XrActionSetCreateInfo setInfo{XR_TYPE_ACTION_SET_CREATE_INFO};
    std::strcpy(setInfo.actionSetName, "sculpting");
    std::strcpy(setInfo.localizedActionSetName, "Sculpting");
    check(xrCreateActionSet(instance, &setInfo, &set_), "xrCreateActionSet", instance);
    hands_ = {path(instance, "/user/hand/left"), path(instance, "/user/hand/right")};
    auto action = [&](XrAction* out, const char* name, const char* label, XrActionType type) {
        XrActionCreateInfo info{XR_TYPE_ACTION_CREATE_INFO};
        info.actionType = type;
        std::strcpy(info.actionName, name);
        std::strcpy(info.localizedActionName, label);
        info.countSubactionPaths = 2;
        info.subactionPaths = hands_.data();
        check(xrCreateAction(set_, &info, out), "xrCreateAction", instance);
    };
    action(&gripPose_, "grip_pose", "Hand", XR_ACTION_TYPE_POSE_INPUT);
    action(&aimPose_, "aim_pose", "Pointing", XR_ACTION_TYPE_POSE_INPUT);
    action(&trigger_, "sculpt", "Sculpt (pressure)", XR_ACTION_TYPE_FLOAT_INPUT);
    action(&squeeze_, "grab_world", "Grab the world", XR_ACTION_TYPE_FLOAT_INPUT);
    action(&thumbstick_, "brush_size_mode", "Brush size and mode / fly", XR_ACTION_TYPE_VECTOR2F_INPUT);
    action(&primary_, "undo_frame", "Undo / frame the scene", XR_ACTION_TYPE_BOOLEAN_INPUT);
    action(&secondary_, "redo_hints", "Redo / controller hints", XR_ACTION_TYPE_BOOLEAN_INPUT);
    action(&menu_, "stats", "Statistics", XR_ACTION_TYPE_BOOLEAN_INPUT);
    action(&haptic_, "touch_pulse", "Touch pulse", XR_ACTION_TYPE_VIBRATION_OUTPUT);

    // Suggested bindings per profile: (action, path under /user/hand/<side>/).
    struct Binding {
        XrAction action;
        const char* input;
        int side; // -1 both, 0 left, 1 right
    };
    auto suggest = [&](const char* profile, const std::vector<Binding>& bindings) {
        std::vector<XrActionSuggestedBinding> suggested;
        for (const Binding& b : bindings)
            for (int side = 0; side < 2; ++side) {
                if (b.side >= 0 && b.side != side) continue;
                suggested.push_back({b.action, path(instance, std::string(side == 0 ? "/user/hand/left/" : "/user/hand/right/") + b.input)});
            }
        XrInteractionProfileSuggestedBinding info{XR_TYPE_INTERACTION_PROFILE_SUGGESTED_BINDING};
        info.interactionProfile = path(instance, profile);
        info.suggestedBindings = suggested.data();
        info.countSuggestedBindings = uint32_t(suggested.size());
        check(xrSuggestInteractionProfileBindings(instance, &info), "xrSuggestInteractionProfileBindings", instance);
    };
    const std::vector<Binding> poses{{gripPose_, "input/grip/pose", -1}, {aimPose_, "input/aim/pose", -1}, {haptic_, "output/haptic", -1}};
    auto with = [&](std::vector<Binding> extra) {
        extra.insert(extra.end(), poses.begin(), poses.end());
        return extra;
    };
    suggest("/interaction_profiles/khr/simple_controller",
            with({{trigger_, "input/select/click", -1}, {menu_, "input/menu/click", -1}}));
    suggest("/interaction_profiles/oculus/touch_controller",
            with({{trigger_, "input/trigger/value", -1},
                  {squeeze_, "input/squeeze/value", -1},
                  {thumbstick_, "input/thumbstick", -1},
                  {primary_, "input/x/click", 0},
                  {secondary_, "input/y/click", 0},
                  {primary_, "input/a/click", 1},
                  {secondary_, "input/b/click", 1},
                  {menu_, "input/menu/click", 0}}));
    suggest("/interaction_profiles/valve/index_controller",
            with({{trigger_, "input/trigger/value", -1},
                  {squeeze_, "input/squeeze/value", -1},
                  {thumbstick_, "input/thumbstick", -1},
                  {primary_, "input/a/click", -1},
                  {secondary_, "input/b/click", -1}}));
    suggest("/interaction_profiles/htc/vive_controller",
            with({{trigger_, "input/trigger/value", -1},
                  {squeeze_, "input/squeeze/click", -1},
                  {thumbstick_, "input/trackpad", -1},
                  {primary_, "input/trackpad/click", -1},
                  {menu_, "input/menu/click", -1}}));

    for (int h = 0; h < 2; ++h) {
        XrActionSpaceCreateInfo info{XR_TYPE_ACTION_SPACE_CREATE_INFO};
        info.subactionPath = hands_[std::size_t(h)];
        info.poseInActionSpace.orientation.w = 1.0f;
        info.action = gripPose_;
        check(xrCreateActionSpace(session, &info, &gripSpaces_[std::size_t(h)]), "xrCreateActionSpace", instance);
        info.action = aimPose_;
        check(xrCreateActionSpace(session, &info, &aimSpaces_[std::size_t(h)]), "xrCreateActionSpace", instance);
    }
    XrSessionActionSetsAttachInfo attach{XR_TYPE_SESSION_ACTION_SETS_ATTACH_INFO};
    attach.countActionSets = 1;
    attach.actionSets = &set_;
    check(xrAttachSessionActionSets(session, &attach), "xrAttachSessionActionSets", instance);
}

XrControllers::~XrControllers()
{
    for (XrSpace s : gripSpaces_)
        if (s) xrDestroySpace(s);
    for (XrSpace s : aimSpaces_)
        if (s) xrDestroySpace(s);
    if (set_) xrDestroyActionSet(set_); // its actions with it
}

ControllerFrame XrControllers::read(XrSpace space, XrTime time, bool focused, double seconds)
{
    ControllerFrame frame;
    frame.seconds = seconds;
    frame.focused = focused;
    if (!focused) return frame;
    XrActiveActionSet active{set_, XR_NULL_PATH};
    XrActionsSyncInfo sync{XR_TYPE_ACTIONS_SYNC_INFO};
    sync.countActiveActionSets = 1;
    sync.activeActionSets = &active;
    const XrResult synced = xrSyncActions(session_, &sync);
    check(synced, "xrSyncActions", instance_);
    if (synced == XR_SESSION_NOT_FOCUSED) {
        frame.focused = false;
        return frame;
    }
    for (int h = 0; h < 2; ++h) {
        HandInput& hand = frame.hands[std::size_t(h)];
        XrActionStateGetInfo get{XR_TYPE_ACTION_STATE_GET_INFO};
        get.subactionPath = hands_[std::size_t(h)];
        auto floatOf = [&](XrAction a) {
            get.action = a;
            XrActionStateFloat s{XR_TYPE_ACTION_STATE_FLOAT};
            check(xrGetActionStateFloat(session_, &get, &s), "xrGetActionStateFloat", instance_);
            return s.isActive ? double(s.currentState) : 0.0;
        };
        auto boolOf = [&](XrAction a) {
            get.action = a;
            XrActionStateBoolean s{XR_TYPE_ACTION_STATE_BOOLEAN};
            check(xrGetActionStateBoolean(session_, &get, &s), "xrGetActionStateBoolean", instance_);
            return s.isActive && s.currentState;
        };
        hand.trigger = floatOf(trigger_);
        hand.squeeze = floatOf(squeeze_);
        get.action = thumbstick_;
        XrActionStateVector2f stick{XR_TYPE_ACTION_STATE_VECTOR2F};
        check(xrGetActionStateVector2f(session_, &get, &stick), "xrGetActionStateVector2f", instance_);
        if (stick.isActive) hand.thumbstick = glm::dvec2(stick.currentState.x, stick.currentState.y);
        hand.primary = boolOf(primary_);
        hand.secondary = boolOf(secondary_);
        hand.menu = boolOf(menu_);
        get.action = gripPose_;
        XrActionStatePose pose{XR_TYPE_ACTION_STATE_POSE};
        check(xrGetActionStatePose(session_, &get, &pose), "xrGetActionStatePose", instance_);
        if (!pose.isActive) continue;
        const XrSpaceLocationFlags needed = XR_SPACE_LOCATION_ORIENTATION_VALID_BIT | XR_SPACE_LOCATION_POSITION_VALID_BIT;
        XrSpaceLocation grip{XR_TYPE_SPACE_LOCATION}, aim{XR_TYPE_SPACE_LOCATION};
        check(xrLocateSpace(gripSpaces_[std::size_t(h)], space, time, &grip), "xrLocateSpace", instance_);
        check(xrLocateSpace(aimSpaces_[std::size_t(h)], space, time, &aim), "xrLocateSpace", instance_);
        if ((grip.locationFlags & needed) != needed) continue;
        hand.tracked = true;
        hand.grip = poseOf(grip.pose);
        hand.aim = (aim.locationFlags & needed) == needed ? poseOf(aim.pose) : hand.grip;
    }
    return frame;
}

void XrControllers::pulse(int hand, double amplitude)
{
    XrHapticVibration vibration{XR_TYPE_HAPTIC_VIBRATION};
    vibration.amplitude = float(amplitude);
    vibration.duration = 20'000'000; // 20 ms
    vibration.frequency = XR_FREQUENCY_UNSPECIFIED;
    XrHapticActionInfo info{XR_TYPE_HAPTIC_ACTION_INFO};
    info.action = haptic_;
    info.subactionPath = hands_[std::size_t(hand)];
    check(xrApplyHapticFeedback(session_, &info, reinterpret_cast<const XrHapticBaseHeader*>(&vibration)), "xrApplyHapticFeedback", instance_);
}

std::string XrControllers::profile(int hand) const
{
    XrInteractionProfileState state{XR_TYPE_INTERACTION_PROFILE_STATE};
    if (XR_FAILED(xrGetCurrentInteractionProfile(session_, hands_[std::size_t(hand)], &state)) || state.interactionProfile == XR_NULL_PATH)
        return {};
    uint32_t count = 0;
    char buffer[XR_MAX_PATH_LENGTH] = {};
    if (XR_FAILED(xrPathToString(instance_, state.interactionProfile, sizeof buffer, &count, buffer))) return {};
    return buffer;
}

} // namespace vdbclay::vr
