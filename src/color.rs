//! The sRGB transfer functions, for every layer that turns bytes into light or back (the
//! CPU twin of the GPU's sRGB formats; `reference::shading` re-exports them).

/// The sRGB transfer function's inverse: an encoded value in [0, 1] to linear.
pub fn srgb_decode(encoded: f32) -> f32 {
    if encoded < 0.04045 {
        encoded / 12.92
    } else {
        ((encoded + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear [0, 1] to an sRGB-encoded byte.
pub fn srgb_encode(linear: f32) -> u8 {
    let l = linear.clamp(0.0, 1.0);
    let s = if l <= 0.0031308 {
        12.92 * l
    } else {
        1.055 * l.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}
