#version 450
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(location = 0) in vec3 inPosition;
layout(location = 1) in vec2 inNormal; // octahedral (octahedralNormal)
layout(location = 2) in uint inPacked; // material (16 bits) | level (7) | masked (1) | occlusion (8)
layout(location = 3) in uint inBlend;  // other material (16) | its share (8) | 0 (7) | blended (1)

layout(location = 0) out vec3 worldPosition;
layout(location = 1) out vec3 worldNormal;
layout(location = 2) flat out uint material;
layout(location = 3) flat out uint level;
layout(location = 4) out float occlusion;
layout(location = 5) out float masked; // 1 where the sculptor's mask keeps the voxel
layout(location = 6) out vec3 blendedColour; // the vertex's material colour mixed with the one beside it
layout(location = 7) out float blended;      // 1 where the vertex carries a blend

/// Folds the square back onto the octahedron (the lower half across its diagonals).
vec3 unfoldNormal(vec2 e)
{
    vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    float t = max(-n.z, 0.0);
    n.x += n.x >= 0.0 ? -t : t;
    n.y += n.y >= 0.0 ? -t : t;
    return normalize(n);
}

void main()
{
    worldPosition = inPosition;
    worldNormal = unfoldNormal(inNormal);
    material = inPacked & 0xffffu;
    level = (inPacked >> 16) & 0x7fu;
    masked = float((inPacked >> 23) & 1u);
    // Colours are mixed here, from the table, so that a material's new colour shows without re-meshing.
    vec3 own = materials.entries[2u * material].rgb;
    uint other = inBlend & 0xffffu;
    float share = float((inBlend >> 16) & 0xffu) / 255.0;
    blendedColour = other != 0u ? mix(own, materials.entries[2u * other].rgb, share) : own;
    blended = float(inBlend >> 31);
    occlusion = float(inPacked >> 24) / 255.0;
    gl_Position = view.viewProj * vec4(inPosition, 1.0);
}
