#version 450
// A panel (a picture of menus) on a quad: its four corners come in clip space, two triangles make it.
layout(push_constant) uniform Quad {
    vec4 corners[4]; // clip space: lower left, lower right, upper right, upper left (as the picture is read)
    vec4 uvRect;     // the picture's part: u0, v0 (upper left), u1, v1
} quad;
layout(location = 0) out vec2 uv;
void main()
{
    const int corner[6] = int[6](0, 1, 2, 0, 2, 3);
    int c = corner[gl_VertexIndex];
    gl_Position = quad.corners[c];
    vec2 t = vec2(c == 1 || c == 2 ? 1.0 : 0.0, c >= 2 ? 0.0 : 1.0);
    uv = mix(quad.uvRect.xy, quad.uvRect.zw, t);
}
