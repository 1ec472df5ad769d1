// The brush's signed distance (world units, negative inside), the same primitives as sculpt's Brush.
float sdBrushLocal(vec3 p)
{
    uint shape = view.mode.z;
    vec4 a = view.brushParams;
    float h = view.brushExtra.x;
    if (shape == 0u) return length(p) - a.x;
    if (shape == 1u) {
        vec3 q = abs(p) - (a.xyz - vec3(a.w));
        return length(max(q, 0.0)) + min(max(q.x, max(q.y, q.z)), 0.0) - a.w;
    }
    if (shape == 2u) {
        vec2 d = abs(vec2(length(p.xz), p.y)) - vec2(a.x, 0.5 * h);
        return min(max(d.x, d.y), 0.0) + length(max(d, 0.0));
    }
    if (shape == 3u) {
        p.y -= clamp(p.y, -0.5 * h, 0.5 * h);
        return length(p) - a.x;
    }
    if (shape == 4u) return length(vec2(length(p.xz) - a.x, p.y)) - a.y;
    // Cone: base radius a.x at y = -h/2, apex at y = +h/2.
    float hh = 0.5 * h;
    float qx = length(p.xz), qy = p.y;
    vec2 cap = vec2(qx - min(qx, qy < 0.0 ? a.x : 0.0), abs(qy) - hh);
    vec2 e = vec2(-a.x, 2.0 * hh);
    float t = clamp(dot(vec2(qx - a.x, qy + hh), e) / dot(e, e), 0.0, 1.0);
    vec2 side = vec2(qx - a.x, qy + hh) - e * t;
    float s = (side.x < 0.0 && cap.y < 0.0) ? -1.0 : 1.0;
    return s * sqrt(min(dot(cap, cap), dot(side, side)));
}

float sdBrush(vec3 world)
{
    vec3 local = (view.brushWorldToLocal * vec4(world, 1.0)).xyz;
    return sdBrushLocal(local) * view.brushExtra.y;
}
