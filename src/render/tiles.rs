//! Per-cluster light lists: which lights can reach each 16 x 16-pixel tile of the screen and each
//! slice of view distance within it, so the lighting pass loops over its cluster's lights rather
//! than all of them. Computed on the CPU each frame from each point and spot light's bounding
//! sphere (position, `range`): projected to the screen for the tiles, conservatively (a sphere
//! that reaches the camera's near plane covers every tile), and its view-distance interval for
//! the slices; directional lights and lights without a range are in every cluster.
//!
//! Slices: view distance d is in slice `clamp(floor(log2(max(d, d0)/d0)·k), 0, S − 1)` with d0 the
//! projection's near distance, k = [`SLICES_PER_OCTAVE`] and S = [`SLICES`] (so the slices are
//! 2^(1/k) deep each, from d0 to d0·2^(S/k), the last open-ended). A sphere's view distances are
//! widened by a relative [`DEPTH_MARGIN`] before they are sliced, so that a pixel the shader puts
//! in a neighbouring slice by rounding still finds the light. A frame without a ranged light
//! (nothing to cull by distance), with an orthographic camera, or whose tiles list fewer than
//! [`SLICE_FROM`] lights on average, has one slice: the tiles alone.
//!
//! Why tiles and slices and not only the per-pixel range test: on a SIMD rasterizer such as
//! lavapipe a branch is skipped only when no lane of the vector takes it, so a light that reaches a
//! few pixels of a vector still costs every pixel its BRDF; a cluster's list is the same for every
//! pixel in it, and neighbouring pixels are mostly in one cluster. The slices matter when many
//! short-range lights overlap on screen at different distances (issue 29 item 2: the tiles alone
//! gave 256 lights 1.77x the frame of 4).
//!
//! Layout of the buffer (u32): per cluster `(offset, count)`, cluster `(slice·rows + y)·columns +
//! x`, then the light indices.

use glam::{Mat4, Vec3, Vec4};

use super::gpu::{FrameData, GpuLight, LIGHT_DIRECTIONAL};

pub use crate::records::{tile_grid, TILE};

/// Depth slices of a frame with ranged lights.
pub const SLICES: u32 = 48;

/// Slices per doubling of the view distance (each slice 19 % deeper than the one before).
pub const SLICES_PER_OCTAVE: f32 = 4.0;

/// The relative margin on a light's view distances: the shader computes a pixel's distance and
/// its logarithm in f32 (a few ulp, and `log2`'s 2^-21 absolute under Vulkan's rules), so a
/// point of the light's sphere at a slice boundary may land in the next slice; 1e-3 is a
/// thousand times that, and 0.6 % of a slice.
const DEPTH_MARGIN: f32 = 1e-3;

/// The light lists of every cluster (see the module docs for the layout) and the frame's
/// `clusters` record (slices, near distance, slices per octave, tile rows) the shader finds its
/// cluster with. With `cull` false every light is in every cluster of one slice; with `slices`
/// false (the plan's `light_slices`: the shader has no slice code) there is one slice.
pub fn tile_lights(
    frame: &FrameData,
    lights: &[GpuLight],
    cull: bool,
    slices: bool,
) -> (Vec<u32>, [f32; 4]) {
    let (flat, one) = sliced_lights(frame, lights, cull, 1);
    if !slices {
        return (flat, one);
    }
    let (tx, ty) = tile_grid(frame.viewport[0] as u32, frame.viewport[1] as u32);
    let tiles = (tx * ty) as usize;
    // Lights listed per tile, on average: the slices pay only where a tile holds many.
    let mean = (flat.len() - 2 * tiles) as f64 / tiles as f64;
    if mean < SLICE_FROM {
        return (flat, one);
    }
    sliced_lights(frame, lights, cull, SLICES)
}

/// The mean number of lights per tile from which a frame's lists are sliced by view distance: a
/// pixel's slice costs its view distance and a logarithm, which on lavapipe made the lighting
/// pass of the default scene with 4 short-range lights 6 % slower (`weft bench --plan`,
/// 960x540: 35.3 against 33.4 ms) where 256 of them were 2.4 times faster (70.6 against 169 ms).
pub const SLICE_FROM: f64 = 8.0;

/// [`tile_lights`] with at most `max_slices` slices.
fn sliced_lights(
    frame: &FrameData,
    lights: &[GpuLight],
    cull: bool,
    max_slices: u32,
) -> (Vec<u32>, [f32; 4]) {
    let (width, height) = (frame.viewport[0] as u32, frame.viewport[1] as u32);
    let (tx, ty) = tile_grid(width, height);
    let view = Mat4::from_cols_array_2d(&frame.view);
    let proj = Mat4::from_cols_array_2d(&frame.proj);
    // Near plane distance of the reversed-Z infinite projection: proj[3][2] = near.
    let near = frame.proj[3][2].abs().max(1e-6);
    // An orthographic projection (w row 0 0 0 1) gets no screen rectangles: every tile.
    let orthographic = frame.proj[3][3] != 0.0;
    let ranged = lights
        .iter()
        .any(|l| l.direction_type[3] != LIGHT_DIRECTIONAL && l.position_range[3] > 0.0);
    let slices = if cull && !orthographic && ranged {
        max_slices.max(1)
    } else {
        1
    };
    let slice_of = |d: f32| -> u32 {
        let s = ((d.max(near) / near).log2() * SLICES_PER_OCTAVE).floor();
        if s.is_nan() {
            0
        } else {
            (s.max(0.0) as u32).min(slices - 1)
        }
    };
    let tiles = (tx * ty) as usize;
    let mut lists: Vec<Vec<u32>> = vec![Vec::new(); tiles * slices as usize];
    for (i, l) in lights.iter().enumerate() {
        let range = l.position_range[3];
        // The view distances the light can reach (every slice when it has no range).
        let mut depth = (0, slices - 1);
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
                // Its slices, from its view distances widened by DEPTH_MARGIN (see the module
                // docs).
                depth = (
                    slice_of((-c.z - range) * (1.0 - DEPTH_MARGIN)),
                    slice_of((-c.z + range) * (1.0 + DEPTH_MARGIN)),
                );
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
        for s in depth.0..=depth.1 {
            for y in y0..=y1 {
                for x in x0..=x1 {
                    lists[((s * ty + y) * tx + x) as usize].push(i as u32);
                }
            }
        }
    }
    let clusters = lists.len();
    let mut out = Vec::with_capacity(2 * clusters + lists.iter().map(Vec::len).sum::<usize>());
    let mut offset = 2 * clusters as u32;
    for l in &lists {
        out.push(offset);
        out.push(l.len() as u32);
        offset += l.len() as u32;
    }
    for l in lists {
        out.extend(l);
    }
    (out, [slices as f32, near, SLICES_PER_OCTAVE, ty as f32])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::records::LIGHT_POINT;

    /// A perspective camera 6 m back and 2 m up, looking at the origin.
    fn camera() -> crate::scene::Camera {
        crate::scene::Camera {
            name: String::new(),
            view: Mat4::look_at_rh(Vec3::new(0.0, 2.0, 6.0), Vec3::ZERO, Vec3::Y),
            yfov: 0.8,
            znear: 0.05,
            zfar: None,
            aspect_ratio: None,
            orthographic: None,
            framing: None,
        }
    }

    /// What shade.glsl's tile_list does for a pixel and its world point, in f32.
    fn cluster_of(frame: &FrameData, clusters: [f32; 4], px: [f32; 2], p: Vec3) -> usize {
        let view = Mat4::from_cols_array_2d(&frame.view);
        let (tx, _) = tile_grid(frame.viewport[0] as u32, frame.viewport[1] as u32);
        let mut slice = 0u32;
        if clusters[0] > 1.5 {
            let d = -(view * p.extend(1.0)).z;
            let s = ((d.max(clusters[1]) / clusters[1]).log2() * clusters[2]).floor();
            slice = s.clamp(0.0, clusters[0] - 1.0) as u32;
        }
        let (x, y) = (px[0] as u32 / TILE, px[1] as u32 / TILE);
        ((slice * (clusters[3] + 0.5) as u32 + y) * tx + x) as usize
    }

    /// Conservative culling: every point within a light's range that a pixel of the image sees
    /// finds the light in its cluster's list. 300 random short-range point lights over a scene
    /// 40 m deep, 20,000 random points near them.
    #[test]
    fn every_point_in_range_finds_its_lights() {
        let camera = camera();
        let (w, h) = (333, 200);
        let frame = FrameData::new(&camera, w, h);
        let mut rng = crate::reference::probe::XorShift::new(29);
        let lights: Vec<GpuLight> = (0..300)
            .map(|_| GpuLight {
                position_range: [
                    rng.range(-8.0, 8.0) as f32,
                    rng.range(-1.0, 3.0) as f32,
                    rng.range(-35.0, 5.8) as f32,
                    rng.log_range(0.05, 3.0) as f32,
                ],
                direction_type: [0.0, -1.0, 0.0, LIGHT_POINT],
                color_intensity: [1.0; 4],
                spot: [0.0; 4],
            })
            .collect();
        let (lists, clusters) = tile_lights(&frame, &lights, true, true);
        assert_eq!(clusters[0], SLICES as f32, "ranged lights: sliced");
        let view_proj = Mat4::from_cols_array_2d(&frame.view_proj);
        let (mut checked, mut total) = (0, 0);
        for _ in 0..20_000 {
            let i = (rng.next_u64() % lights.len() as u64) as usize;
            let l = &lights[i];
            let dir = Vec3::from_array(rng.unit().map(|x| x as f32));
            let r = l.position_range[3] * rng.next_f64().powf(1.0 / 3.0) as f32 * 0.999;
            let p = Vec3::new(
                l.position_range[0],
                l.position_range[1],
                l.position_range[2],
            ) + dir * r;
            let clip = view_proj * p.extend(1.0);
            if clip.w <= 0.0 {
                continue;
            }
            let ndc = clip.truncate() / clip.w;
            if ndc.x.abs() >= 1.0 || ndc.y.abs() >= 1.0 || ndc.z <= 0.0 {
                continue;
            }
            let px = [
                (ndc.x * 0.5 + 0.5) * w as f32,
                (ndc.y * 0.5 + 0.5) * h as f32,
            ];
            let c = cluster_of(&frame, clusters, px, p);
            let (offset, count) = (lists[2 * c] as usize, lists[2 * c + 1] as usize);
            total += count;
            checked += 1;
            assert!(
                lists[offset..offset + count].contains(&(i as u32)),
                "light {i} at {:?} misses the point {p} (pixel {px:?}, cluster {c})",
                l.position_range
            );
        }
        assert!(checked > 5_000, "{checked} points checked");
        // The slices cut the lists: the same points' lists with the tiles alone.
        let (flat, one) = sliced_lights(&frame, &lights, true, 1);
        assert_eq!(one[0], 1.0);
        let mut rng = crate::reference::probe::XorShift::new(30);
        let (mut sliced_sum, mut flat_sum, mut n) = (0usize, 0usize, 0usize);
        for _ in 0..5_000 {
            let p = Vec3::new(
                rng.range(-8.0, 8.0) as f32,
                rng.range(-1.0, 3.0) as f32,
                rng.range(-35.0, 5.8) as f32,
            );
            let clip = view_proj * p.extend(1.0);
            let ndc = clip.truncate() / clip.w;
            if clip.w <= 0.0 || ndc.x.abs() >= 1.0 || ndc.y.abs() >= 1.0 {
                continue;
            }
            let px = [
                (ndc.x * 0.5 + 0.5) * w as f32,
                (ndc.y * 0.5 + 0.5) * h as f32,
            ];
            sliced_sum += lists[2 * cluster_of(&frame, clusters, px, p) + 1] as usize;
            flat_sum += flat[2 * cluster_of(&frame, one, px, p) + 1] as usize;
            n += 1;
        }
        println!(
            "lights per point's list over {n} points in view: {:.1} sliced, {:.1} tiles alone",
            sliced_sum as f64 / n as f64,
            flat_sum as f64 / n as f64
        );
        assert!(sliced_sum * 2 < flat_sum, "{sliced_sum} against {flat_sum}");
        println!(
            "{checked} points, mean list {:.1} lights",
            total as f64 / checked as f64
        );
    }

    /// Without a ranged light there is nothing to slice: one slice, as the tiles alone.
    #[test]
    fn directional_lights_alone_keep_one_slice() {
        let camera = camera();
        let frame = FrameData::new(&camera, 64, 48);
        let sun = GpuLight {
            position_range: [0.0; 4],
            direction_type: [0.0, -1.0, 0.0, LIGHT_DIRECTIONAL],
            color_intensity: [1.0; 4],
            spot: [0.0; 4],
        };
        let (lists, clusters) = tile_lights(&frame, &[sun, sun], true, true);
        assert_eq!(clusters[0], 1.0);
        let tiles = 4 * 3;
        assert_eq!(lists.len(), 2 * tiles + 2 * tiles);
    }
}
