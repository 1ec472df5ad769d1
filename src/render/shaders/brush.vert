#version 450
// One triangle covering the screen; the fragment shader ray-marches the brush.
layout(location = 0) out vec2 ndc;
void main()
{
    vec2 p = vec2(float((gl_VertexIndex << 1) & 2), float(gl_VertexIndex & 2));
    ndc = p * 2.0 - 1.0;
    gl_Position = vec4(ndc, 0.0, 1.0);
}
