// The stroke script from the issue text, used by several test files.
#pragma once

namespace vdbclay::test {

inline const char* kExampleScript = R"json({ "materials": [ {"name": "stone", "color": [0.6,0.6,0.6,1], "toughness": 0.9} ],
  "ops": [
    {"mode": "add", "brush": {"shape": "sphere", "radius": 20}, "at": [0,0,0], "material": "stone"},
    {"mode": "remove", "brush": {"shape": "box", "size": [8,8,30], "rounding": 1}, "at": [10,0,0], "rotate": [0,0,30]},
    {"mode": "paint", "brush": {"shape": "sphere", "radius": 6}, "path": [[0,0,20],[15,0,15]], "material": "default"},
    {"mode": "erode", "brush": {"shape": "capsule", "radius": 4, "length": 10}, "at": [0,18,0], "strength": 1.0},
    {"mode": "add", "brush": {"shape": "blend", "smoothness": 2.0, "parts": [
        {"shape": "sphere", "radius": 5, "at": [0,0,0]},
        {"shape": "box", "size": [3,3,3], "at": [4,0,0], "op": "remove"}]},
     "at": [0,-25,0], "scale": [1,2,1]}
  ] })json";

} // namespace vdbclay::test
