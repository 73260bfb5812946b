// For a window (ppm-vk view): the resolved image (linear RGB, resolve.comp) scaled by 2^exposure, clamped to
// [0, 1] and sRGB-encoded to 8 bits as RgbImage::save_png does (NaN black), fitted into the window by nearest
// neighbour with bars around it, packed in the swapchain's byte order. One thread per window pixel.
#version 460
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Image { vec4 image[]; };
layout(std430, binding = 1) writeonly buffer Frame { uint frame[]; };
layout(push_constant) uniform TonemapPush {
    uint src_width;   // the image
    uint src_height;
    uint dst_width;   // the window
    uint dst_height;
    int offset_x;     // where the image's top-left pixel lands in the window
    int offset_y;
    float scale;      // window pixels per image pixel
    float gain;       // 2^exposure
    uint bgra;        // 1: bytes B, G, R, A; 0: R, G, B, A
    uint background;  // the bars' packed texel
    uint pad0;
    uint pad1;
} pc;
#include "invocation.glsl"

// The sRGB OETF (IEC 61966-2-1), quantised to 8 bits (image_io.rs's srgb_encode_u8).
uint srgb_u8(float linear) {
    float v = isnan(linear) ? 0.0 : clamp(linear, 0.0, 1.0);
    float e = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
    return uint(clamp(floor(e * 255.0 + 0.5), 0.0, 255.0));
}

void main() {
    uint i = invocation_index();
    if (i >= pc.dst_width * pc.dst_height) return;
    int x = int(i % pc.dst_width) - pc.offset_x;
    int y = int(i / pc.dst_width) - pc.offset_y;
    int sx = int(floor(float(x) / pc.scale));
    int sy = int(floor(float(y) / pc.scale));
    if (x < 0 || y < 0 || sx >= int(pc.src_width) || sy >= int(pc.src_height)) {
        frame[i] = pc.background;
        return;
    }
    vec3 c = image[uint(sy) * pc.src_width + uint(sx)].rgb * pc.gain;
    uint r = srgb_u8(c.r), g = srgb_u8(c.g), b = srgb_u8(c.b);
    frame[i] = pc.bgra != 0u ? (b | g << 8 | r << 16 | 255u << 24) : (r | g << 8 | b << 16 | 255u << 24);
}
