#version 450
#extension GL_EXT_samplerless_texture_functions : require
// The least reversed depth (the farthest surface) of each 8 x 8 tile of a view's pixels: one workgroup
// per tile, reduced in shared memory.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform texture2D depthImage;
layout(set = 0, binding = 1) writeonly buffer Tiles { float least[]; } tiles;
layout(push_constant) uniform Region {
    ivec4 viewport; // x, y, width, height in pixels
    int columns;    // tiles per row
} region;

shared float partial[64];

void main()
{
    const ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    // Pixels past the viewport's edge (the last row and column of tiles) take no part: depth is at most 1.
    float depth = 2.0;
    if (pixel.x < region.viewport.z && pixel.y < region.viewport.w) depth = texelFetch(depthImage, region.viewport.xy + pixel, 0).r;
    const uint index = gl_LocalInvocationIndex;
    partial[index] = depth;
    barrier();
    for (uint stride = 32u; stride > 0u; stride >>= 1u) {
        if (index < stride) partial[index] = min(partial[index], partial[index + stride]);
        barrier();
    }
    if (index == 0u) tiles.least[gl_WorkGroupID.y * uint(region.columns) + gl_WorkGroupID.x] = partial[0];
}
