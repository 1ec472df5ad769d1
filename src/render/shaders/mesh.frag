#version 450
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "brush.glsl"

layout(location = 0) in vec3 worldPosition;
layout(location = 1) in vec3 worldNormal;
layout(location = 2) flat in uint material;
layout(location = 3) flat in uint level;
layout(location = 4) in float occlusion;
layout(location = 5) in float masked;
layout(location = 6) in vec3 blendedColour;
layout(location = 7) in float blended;

layout(push_constant) uniform Push {
    vec4 tint; // rgb, a = 1: a flat colour (wireframe lines)
} push;

layout(location = 0) out vec4 outColour;

float hash3(vec3 p)
{
    p = fract(p * 0.3183099 + vec3(0.71, 0.113, 0.419));
    p *= 17.0;
    return fract(p.x * p.y * p.z * (p.x + p.y + p.z));
}

// Value noise in 2D (one plane of the tri-planar projection), seeded per material.
float noise2(vec2 x, float seed)
{
    vec2 i = floor(x), f = fract(x);
    vec2 u = f * f * (3.0 - 2.0 * f);
    float a = hash3(vec3(i, seed)), b = hash3(vec3(i + vec2(1, 0), seed));
    float c = hash3(vec3(i + vec2(0, 1), seed)), d = hash3(vec3(i + vec2(1, 1), seed));
    return mix(mix(a, b, u.x), mix(c, d, u.x), u.y);
}

float fbm2(vec2 x, float seed)
{
    return 0.55 * noise2(x, seed) + 0.3 * noise2(2.03 * x, seed + 7.0) + 0.15 * noise2(4.01 * x, seed + 13.0);
}

// Tri-planar texturing (seed 004 §4.2.4): three planar projections blended by the normal's components.
float triplanar(vec3 p, vec3 n, float seed)
{
    vec3 w = pow(abs(n), vec3(4.0));
    w /= (w.x + w.y + w.z);
    return w.x * fbm2(p.yz, seed) + w.y * fbm2(p.zx, seed) + w.z * fbm2(p.xy, seed);
}

// The same projection for a material's picture: three samples blended by the normal. The mipmap comes
// from the pixel's footprint (distance times a pixel's angle, `scale` texture repetitions per world unit),
// not from screen derivatives: a mesh's slivers make helper invocations extrapolate far off the surface.
vec3 triplanarPicture(vec3 p, vec3 n, float layer, float footprint)
{
    vec3 w = pow(abs(n), vec3(4.0));
    w /= (w.x + w.y + w.z);
    vec2 dx = vec2(footprint, 0.0), dy = vec2(0.0, footprint);
    return w.x * textureGrad(pictures, vec3(p.yz, layer), dx, dy).rgb +
           w.y * textureGrad(pictures, vec3(p.zx, layer), dx, dy).rgb +
           w.z * textureGrad(pictures, vec3(p.xy, layer), dx, dy).rgb;
}

const vec3 kLevelColours[8] = vec3[8](vec3(0.90, 0.30, 0.25), vec3(0.95, 0.65, 0.20), vec3(0.85, 0.85, 0.25),
                                       vec3(0.35, 0.80, 0.35), vec3(0.25, 0.75, 0.80), vec3(0.30, 0.45, 0.90),
                                       vec3(0.60, 0.35, 0.85), vec3(0.85, 0.40, 0.70));

// Masked surface shows darkened (as sculpting tools show a mask), whatever the shading.
const float kMaskedShade = 0.35;

void main()
{
    if (push.tint.a > 0.5) {
        outColour = vec4(push.tint.rgb, 1.0);
        return;
    }
    vec3 n = normalize(worldNormal);
    if (!gl_FrontFacing) n = -n;
    vec3 l = normalize(-view.lightDir.xyz);
    float diffuse = max(dot(n, l), 0.0);
    float ao = view.lightDir.w > 0.5 ? occlusion : 1.0;
    vec4 m0 = materials.entries[2u * material];
    vec4 m1 = materials.entries[2u * material + 1u];
    // Where the mesh carries blends, colours run smoothly across material boundaries (a soft paint
    // stroke's edge); the triangle's own material still picks the pattern or picture.
    vec3 tint = mix(m0.rgb, blendedColour, blended);

    vec3 base;
    uint mode = view.mode.x;
    if (mode == 3u) {
        outColour = vec4(0.5 * n + 0.5, 1.0); // the normal itself, not gamma-encoded
        return;
    } else if (mode == 4u) {
        // Clay: a light that travels with the viewer (from above its shoulder), a soft wrap and a rim, as
        // a sculptor's matcap reads the form whatever the materials are.
        vec3 v = normalize(view.eye.xyz - worldPosition);
        vec3 key = normalize(v + vec3(0.0, 1.2, 0.0));
        float diffuse = max(dot(n, key), 0.0);
        float facing = clamp(dot(n, v), 0.0, 1.0);
        float rim = pow(1.0 - facing, 4.0);
        // Form reads from the light's falloff and the occlusion in creases; faces turned from the viewer
        // darken, as a matcap's sphere does towards its edge.
        vec3 clay = vec3(0.70, 0.60, 0.52) * (0.12 + 0.88 * diffuse * diffuse) * mix(0.55, 1.0, facing) * mix(1.0, ao, 0.8) +
                    vec3(0.16, 0.17, 0.20) * rim;
        clay *= mix(1.0, kMaskedShade, masked);
        if ((view.mode.y & 2u) != 0u && sdBrush(worldPosition) <= 0.0)
            clay = mix(clay, view.highlightColour.rgb, view.highlightColour.a);
        outColour = vec4(pow(clay, vec3(1.0 / 2.2)), 1.0);
        return;
    } else if (mode == 1u) {
        base = kLevelColours[level % 8u];
    } else if (mode == 2u) {
        float t = clamp(m1.x, 0.0, 1.0);
        base = mix(vec3(0.15, 0.35, 0.95), vec3(0.95, 0.2, 0.15), t);
    } else if (m1.w > 0.5) {
        float footprint = view.eye.w * distance(view.eye.xyz, worldPosition) * m1.z;
        base = tint * triplanarPicture(worldPosition * m1.z, n, m1.w - 1.0, footprint);
    } else {
        float grain = triplanar(worldPosition * m1.z, n, m1.y);
        base = tint * (0.82 + 0.36 * grain);
    }
    vec3 colour = base * (0.28 * ao + 0.72 * diffuse * mix(1.0, ao, 0.5)) * mix(1.0, kMaskedShade, masked);
    if ((view.mode.y & 2u) != 0u && sdBrush(worldPosition) <= 0.0)
        colour = mix(colour, view.highlightColour.rgb, view.highlightColour.a);
    outColour = vec4(pow(colour, vec3(1.0 / 2.2)), 1.0); // linear to display (the target is UNORM)
}
