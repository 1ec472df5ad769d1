#version 450
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(location = 0) in vec3 inPosition;
layout(location = 1) in vec3 inNormal;
layout(location = 2) in uint inPacked; // material (16 bits) | level (8) | occlusion (8)

layout(location = 0) out vec3 worldPosition;
layout(location = 1) out vec3 worldNormal;
layout(location = 2) flat out uint material;
layout(location = 3) flat out uint level;
layout(location = 4) out float occlusion;
// The vertex's material colour, blended across triangles: a boundary between materials (a soft paint
// stroke's edge) reads as a gradient, not a staircase.
layout(location = 5) out vec3 materialColour;

void main()
{
    worldPosition = inPosition;
    worldNormal = inNormal;
    material = inPacked & 0xffffu;
    level = (inPacked >> 16) & 0xffu;
    occlusion = float(inPacked >> 24) / 255.0;
    materialColour = materials.entries[2u * material].rgb;
    gl_Position = view.viewProj * vec4(inPosition, 1.0);
}
