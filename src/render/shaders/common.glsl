// Shared by every shader: the per-view uniform block and the material table.
layout(set = 0, binding = 0) uniform ViewData {
    mat4 viewProj;
    mat4 invViewProj;
    vec4 eye;            // xyz: camera position; w: a pixel's size per unit of distance
    vec4 lightDir;       // xyz: direction the key light travels; w: 1 = ambient occlusion on
    uvec4 mode;          // x: view mode, y: brush flags (1 preview, 2 highlight), z: brush shape
    mat4 brushWorldToLocal;
    vec4 brushParams;    // radius / half extents + rounding / torus radii
    vec4 brushExtra;     // x: height or length, y: local-to-world distance scale
    vec4 brushMin;       // the brush's world bounds (preview ray march)
    vec4 brushMax;
    vec4 previewColour;
    vec4 highlightColour;
} view;

layout(std430, set = 0, binding = 1) readonly buffer MaterialTable {
    vec4 entries[]; // two per material: linear RGBA; x toughness, y pattern seed, z pattern frequency
                    // (1 / world unit), w picture layer + 1 (0: the procedural pattern)
} materials;

layout(set = 0, binding = 2) uniform sampler2DArray pictures; // the materials' textures, sRGB
