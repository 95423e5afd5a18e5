//! Per-tile light lists: which lights can reach each 16 x 16-pixel tile of the screen, so the
//! lighting pass loops over a tile's lights rather than all of them. Computed on the CPU each
//! frame from each point and spot light's bounding sphere (position, `range`) projected to the
//! screen, conservatively: a sphere that reaches the camera's near plane covers every tile;
//! directional lights and lights without a range are in every tile.
//!
//! Why tiles and not only the per-pixel range test: on a SIMD rasterizer such as lavapipe a branch
//! is skipped only when no lane of the vector takes it, so a light that reaches a few pixels of a
//! vector still costs every pixel its BRDF; a tile's list is the same for every pixel in it.
//!
//! Layout of the buffer (u32): per tile `(offset, count)`, row-major, then the light indices.

use glam::{Mat4, Vec3, Vec4};

use super::gpu::{FrameData, GpuLight, LIGHT_DIRECTIONAL};

pub use crate::records::{tile_grid, TILE};

/// The light lists of every tile (see the module docs for the layout). With `cull` false every
/// light is in every tile.
pub fn tile_lights(frame: &FrameData, lights: &[GpuLight], cull: bool) -> Vec<u32> {
    let (width, height) = (frame.viewport[0] as u32, frame.viewport[1] as u32);
    let (tx, ty) = tile_grid(width, height);
    let tiles = (tx * ty) as usize;
    let view = Mat4::from_cols_array_2d(&frame.view);
    let proj = Mat4::from_cols_array_2d(&frame.proj);
    // Near plane distance of the reversed-Z infinite projection: proj[3][2] = near.
    let near = frame.proj[3][2].abs().max(1e-6);
    let mut lists: Vec<Vec<u32>> = vec![Vec::new(); tiles];
    for (i, l) in lights.iter().enumerate() {
        let range = l.position_range[3];
        // An orthographic projection (w row 0 0 0 1) gets no screen rectangles: every tile.
        let orthographic = frame.proj[3][3] != 0.0;
        let rect =
            if !cull || orthographic || l.direction_type[3] == LIGHT_DIRECTIONAL || range <= 0.0 {
                None
            } else {
                let c = view.transform_point3(Vec3::new(
                    l.position_range[0],
                    l.position_range[1],
                    l.position_range[2],
                ));
                if c.z - range > -near {
                    // Wholly nearer than the near plane: lights nothing on screen.
                    continue;
                }
                if c.z + range > -near {
                    // Crosses the near plane: its projection is unbounded.
                    None
                } else {
                    // In front: the bounding box of the sphere's box corners on screen.
                    let (mut lo, mut hi) = (
                        glam::Vec2::splat(f32::INFINITY),
                        glam::Vec2::splat(f32::NEG_INFINITY),
                    );
                    for k in 0..8 {
                        let corner = c + Vec3::new(
                            if k & 1 == 0 { -range } else { range },
                            if k & 2 == 0 { -range } else { range },
                            if k & 4 == 0 { -range } else { range },
                        );
                        let p: Vec4 = proj * corner.extend(1.0);
                        let ndc = p.truncate().truncate() / p.w;
                        lo = lo.min(ndc);
                        hi = hi.max(ndc);
                    }
                    if !(lo.is_finite() && hi.is_finite()) {
                        None
                    } else {
                        // NDC to pixels (Vulkan: y down; the projection already flips y).
                        let px = |v: f32, size: u32| (v * 0.5 + 0.5) * size as f32;
                        let x0 = px(lo.x, width).floor();
                        let x1 = px(hi.x, width).ceil();
                        let y0 = px(lo.y, height).floor();
                        let y1 = px(hi.y, height).ceil();
                        if x1 < 0.0 || y1 < 0.0 || x0 > width as f32 || y0 > height as f32 {
                            continue;
                        }
                        let t = |v: f32, n: u32| ((v.max(0.0) as u32) / TILE).min(n - 1);
                        Some((t(x0, tx), t(y0, ty), t(x1, tx), t(y1, ty)))
                    }
                }
            };
        let (x0, y0, x1, y1) = rect.unwrap_or((0, 0, tx - 1, ty - 1));
        for y in y0..=y1 {
            for x in x0..=x1 {
                lists[(y * tx + x) as usize].push(i as u32);
            }
        }
    }
    let mut out = Vec::with_capacity(2 * tiles + lists.iter().map(Vec::len).sum::<usize>());
    let mut offset = 2 * tiles as u32;
    for l in &lists {
        out.push(offset);
        out.push(l.len() as u32);
        offset += l.len() as u32;
    }
    for l in lists {
        out.extend(l);
    }
    out
}
