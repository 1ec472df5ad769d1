#version 450
// The panel's picture, premultiplied by its alpha (as Dear ImGui draws into a cleared, transparent image).
layout(set = 0, binding = 0) uniform sampler2D picture;
layout(location = 0) in vec2 uv;
layout(location = 0) out vec4 colour;
void main()
{
    colour = texture(picture, uv);
}
