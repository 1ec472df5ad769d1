#version 450
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "brush.glsl"

// The translucent brush preview: sphere tracing of the brush's field, depth-tested against the scene.
layout(location = 0) in vec2 ndc;
layout(location = 0) out vec4 outColour;

vec2 boxHits(vec3 o, vec3 d, vec3 lo, vec3 hi)
{
    vec3 inv = 1.0 / d;
    vec3 t0 = (lo - o) * inv, t1 = (hi - o) * inv;
    vec3 tmin = min(t0, t1), tmax = max(t0, t1);
    return vec2(max(max(tmin.x, tmin.y), tmin.z), min(min(tmax.x, tmax.y), tmax.z));
}

void main()
{
    // Depth is reversed with the far plane at infinity: 1 is the near plane, 0 is infinitely far. The ray
    // leaves the eye towards the pixel's point at infinity (w = 0 there, so its xyz is the direction):
    // two unprojected points near the eye would differ by less than float resolves once the near plane
    // hugs the surface (up close), and the rays came out in blocks of pixels.
    vec4 farH = view.invViewProj * vec4(ndc, 0.0, 1.0);
    vec3 o = view.eye.xyz;
    vec3 d = normalize(farH.xyz - farH.w * o);
    vec2 span = boxHits(o, d, view.brushMin.xyz, view.brushMax.xyz);
    if (span.y < max(span.x, 0.0)) discard;
    float t = max(span.x, 0.0);
    float extent = length(view.brushMax.xyz - view.brushMin.xyz);
    bool hit = false;
    for (int i = 0; i < 96 && t <= span.y; ++i) {
        float s = sdBrush(o + t * d);
        if (s < 1e-3 * extent) {
            hit = true;
            break;
        }
        t += s;
    }
    if (!hit) discard;
    vec3 p = o + t * d;
    float e = 1e-3 * extent;
    vec3 n = normalize(vec3(sdBrush(p + vec3(e, 0, 0)) - sdBrush(p - vec3(e, 0, 0)),
                            sdBrush(p + vec3(0, e, 0)) - sdBrush(p - vec3(0, e, 0)),
                            sdBrush(p + vec3(0, 0, e)) - sdBrush(p - vec3(0, 0, e))));
    vec4 clip = view.viewProj * vec4(p, 1.0);
    gl_FragDepth = clip.z / clip.w;
    float rim = 1.0 - abs(dot(n, d));
    float light = 0.45 + 0.55 * max(dot(n, normalize(-view.lightDir.xyz)), 0.0);
    outColour = vec4(view.previewColour.rgb * light + vec3(0.35 * rim), view.previewColour.a + 0.35 * rim);
}
