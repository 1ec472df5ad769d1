#include "vr/XrCheck.h"

#include <openxr/openxr_reflection.h>

namespace vdbclay::vr {

std::string resultName(XrResult result, XrInstance instance)
{
    if (instance != XR_NULL_HANDLE) {
        char buffer[XR_MAX_RESULT_STRING_SIZE] = {};
        if (XR_SUCCEEDED(xrResultToString(instance, result, buffer)) && buffer[0]) return buffer;
    }
#define VDBCLAY_XR_RESULT(name, value) \
    case name: return #name;
    switch (result) {
        XR_LIST_ENUM_XrResult(VDBCLAY_XR_RESULT)
    default: return "XrResult " + std::to_string(int(result));
    }
#undef VDBCLAY_XR_RESULT
}

void check(XrResult result, const char* what, XrInstance instance)
{
    if (XR_FAILED(result)) throw XrError(std::string(what) + " failed: " + resultName(result, instance));
}

} // namespace vdbclay::vr
