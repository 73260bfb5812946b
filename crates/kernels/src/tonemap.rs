//! For a window, after stage 5: `shaders/resolve/tonemap.comp`, the resolved image as the 8-bit sRGB texels
//! a swapchain image shows (exposure, clamp, the sRGB OETF, fitted into the window).

use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use ppm_vk_device::{vk, Buffer, ComputePipeline};

use crate::push_struct;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TonemapPush {
    pub src_width: u32,
    pub src_height: u32,
    pub dst_width: u32,
    pub dst_height: u32,
    /// Where the image's top-left pixel lands in the window.
    pub offset_x: i32,
    pub offset_y: i32,
    /// Window pixels per image pixel.
    pub scale: f32,
    /// 2^exposure.
    pub gain: f32,
    /// 1: bytes in B, G, R, A order; 0: R, G, B, A.
    pub bgra: u32,
    /// The packed texel around the image.
    pub background: u32,
    pub pad0: u32,
    pub pad1: u32,
}
push_struct!(TonemapPush, TONEMAP);

impl TonemapPush {
    /// The image of `src` pixels shown in a window of `dst` pixels: at its own size where it fits (so a
    /// window of the image's size shows it pixel for pixel), else shrunk to fit, centred.
    pub fn fit(src: (u32, u32), dst: (u32, u32), exposure: f32, bgra: bool) -> TonemapPush {
        let fit = (dst.0 as f32 / src.0 as f32).min(dst.1 as f32 / src.1 as f32);
        let scale = fit.min(1.0);
        let shown = |n: u32| (n as f32 * scale).floor() as i32;
        TonemapPush {
            src_width: src.0,
            src_height: src.1,
            dst_width: dst.0,
            dst_height: dst.1,
            offset_x: (dst.0 as i32 - shown(src.0)) / 2,
            offset_y: (dst.1 as i32 - shown(src.1)) / 2,
            scale,
            gain: exposure.exp2(),
            bgra: bgra as u32,
            // A dark grey, the same in either byte order.
            background: 0xff20_2020,
            pad0: 0,
            pad1: 0,
        }
    }
}

pub fn record(
    k: &ComputePipeline,
    cmd: vk::CommandBuffer,
    image: &Buffer,
    frame: &Buffer,
    push: &TonemapPush,
) -> Result<()> {
    k.dispatch(
        cmd,
        &[image, frame],
        bytemuck::bytes_of(push),
        push.dst_width as u64 * push.dst_height as u64,
    )
}
