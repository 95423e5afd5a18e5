//! The weave texture: one full pattern repeat (so it tiles with REPEAT addressing), each mip level
//! built directly by `glsl/weave.comp` with the exact coverage of each texel's footprint, not by
//! downsampling the level above.
//!
//! Texel `(x, y)` of a level of `W × H` texels covers `[x/W, (x+1)/W] × [y/H, (y+1)/H]` of the repeat
//! (row `y = 0` is `v = 0`: sample at `st = (u, v)·cell_per_uv / (cols, rows)`, no flip) and holds
//! `(c_warp, c_weft, s_warp, s_weft)`: the area fractions of warp and weft on top and each
//! weighted by the diffuse shadow factor (see `reference::weave`). These are linear in area, so trilinear and
//! anisotropic filtering of them is again a correct footprint average.

use crate::reference::weave::single::{weave_box, Weave};

/// Texels per cell at level 0: enough that a magnified cell (where the point classifier, not the
/// texture, is used) is still smooth, and that the gap of a 10 % gap weave spans 3 texels.
pub const WEAVE_TEXELS_PER_CELL: u32 = 32;

/// Largest difference allowed between a texel of the GPU texture (RGBA16F) and
/// [`weave_texels_cpu`]: one f16 ulp at 1.0 (2^-10: the store rounds to nearest or toward zero,
/// the spec allows either) plus the difference between two f32 evaluations of the same
/// operations (GPU division is 2.5 ulp, products may be fused): a few ulp of coordinates ≤ 8 per
/// boundary, divided by the texel size 1/32 cell, < 1e-4 — taken as 2^-12.
pub const WEAVE_TEXEL_TOLERANCE: f32 = 1.0 / 1024.0 + 1.0 / 4096.0;

/// Push constants of `glsl/weave.comp` (std430 push-constant block, 36 bytes).
///
/// | offset | field | meaning |
/// |---|---|---|
/// | 0  | `pattern_lo: uint` | weft-up bits of rows 0..4, bit `8j + i` = cell (i, j) |
/// | 4  | `pattern_hi: uint` | rows 4..8 |
/// | 8  | `cols: uint` | cells along u, 1..8 |
/// | 12 | `rows: uint` | cells along v, 1..8 |
/// | 16 | `gap: float` | `s_g/s_p`: half the gap, in cells |
/// | 20 | `shadow_dist: float` | `shadow_width/2`, in cells |
/// | 24 | `shadow_strength: float` | |
/// | 28 | `width: uint` | this level's width in texels |
/// | 32 | `height: uint` | this level's height |
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct WeavePush {
    pub pattern_lo: u32,
    pub pattern_hi: u32,
    pub cols: u32,
    pub rows: u32,
    pub gap: f32,
    pub shadow_dist: f32,
    pub shadow_strength: f32,
    pub width: u32,
    pub height: u32,
}

const _: () = {
    assert!(std::mem::size_of::<WeavePush>() == 36);
    assert!(std::mem::offset_of!(WeavePush, gap) == 16);
    assert!(std::mem::offset_of!(WeavePush, width) == 28);
};

impl WeavePush {
    /// The push constants' bytes (little-endian).
    pub fn to_bytes(&self) -> [u8; 36] {
        // The struct is #[repr(C)] and Pod with no padding: its bytes are the push-constant layout.
        bytemuck::bytes_of(self)
            .try_into()
            .expect("the size is asserted at compile time")
    }

    /// The same push constants for another level size.
    pub fn with_size(&self, width: u32, height: u32) -> WeavePush {
        WeavePush {
            width,
            height,
            ..*self
        }
    }
}

/// The recommended level-0 size of a pattern's texture: [`WEAVE_TEXELS_PER_CELL`] per cell
/// (so every texel border lies on a multiple of 1/32 cell: exact in f32).
pub fn weave_level0_size(pattern: &super::WeavePattern) -> (u32, u32) {
    (
        WEAVE_TEXELS_PER_CELL * pattern.cols() as u32,
        WEAVE_TEXELS_PER_CELL * pattern.rows() as u32,
    )
}

/// The size of mip `level` in Vulkan's convention: `max(1, floor(size / 2^level))`.
pub fn weave_level_size(level0: (u32, u32), level: u32) -> (u32, u32) {
    (
        (level0.0 >> level.min(31)).max(1),
        (level0.1 >> level.min(31)).max(1),
    )
}

/// The number of levels of a full mip chain down to 1 × 1.
pub fn weave_mip_count(level0: (u32, u32)) -> u32 {
    32 - level0.0.max(level0.1).max(1).leading_zeros()
}

/// The texels `weave.comp` writes for `push` (`push.width × push.height`, row `y` after row `y-1`),
/// computed on the CPU by the same f32 code (`reference::weave::single::weave_box`), before the
/// GPU's rounding to f16.
pub fn weave_texels_cpu(push: &WeavePush) -> Vec<[f32; 4]> {
    let w = Weave::from_push(push);
    let sx = push.cols as f32 / push.width as f32;
    let sy = push.rows as f32 / push.height as f32;
    let mut out = Vec::with_capacity((push.width * push.height) as usize);
    for y in 0..push.height {
        for x in 0..push.width {
            let c = weave_box(
                &w,
                x as f32 * sx,
                y as f32 * sy,
                (x + 1) as f32 * sx,
                (y + 1) as f32 * sy,
            );
            out.push(c);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fabric::{FabricParams, WeavePattern};

    #[test]
    fn sizes() {
        assert_eq!(weave_level0_size(&WeavePattern::plain()), (64, 64));
        assert_eq!(weave_level0_size(&WeavePattern::satin()), (160, 160));
        assert_eq!(weave_mip_count((160, 160)), 8);
        assert_eq!(weave_mip_count((64, 64)), 7);
        assert_eq!(weave_mip_count((1, 1)), 1);
        assert_eq!(weave_level_size((160, 160), 6), (2, 2));
        assert_eq!(weave_level_size((64, 128), 7), (1, 1));
    }

    #[test]
    fn the_last_level_is_the_repeat_average() {
        let p = FabricParams::default();
        let t = weave_texels_cpu(&p.weave_push(1, 1));
        let g = (p.gap / p.repeat) as f64;
        let cw = (1.0 - 4.0 * g * g) / 2.0;
        assert!(
            (t[0][0] as f64 - cw).abs() < 1e-6 && (t[0][1] as f64 - cw).abs() < 1e-6,
            "{t:?}"
        );
    }
}
