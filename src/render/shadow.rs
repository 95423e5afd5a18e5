//! Shadow maps: where each shadow-casting light's map sits in the atlas, and the light's
//! projection. Plain math, computed before any GPU work (the plan says which lights get one).
//!
//! Every map is a square tile of one D32 atlas, reversed-Z like the camera (nearest to the light
//! is 1), so the lighting pass compares with `GREATER_OR_EQUAL`. Directional lights get an
//! orthographic projection fitted around the bounds of the scene's geometry (every caster and
//! receiver inside, nothing wasted outside the scene); spot lights a perspective projection from
//! the light covering the outer cone, with an infinite far plane.

use glam::{Mat4, Vec3};

use crate::scene::{Bounds, Light, LightKind};

use super::gpu::GpuShadow;
use super::plan::ShadowPlan;

/// The atlas: `cells` x `cells` square cells of `cell` texels; a light's tile is the top-left
/// `resolution` x `resolution` of its cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AtlasLayout {
    pub cells: u32,
    pub cell: u32,
}

impl AtlasLayout {
    pub fn new(shadows: &[ShadowPlan]) -> AtlasLayout {
        let n = shadows.len().max(1) as u32;
        let mut cells = 1;
        while cells * cells < n {
            cells += 1;
        }
        let cell = shadows.iter().map(|s| s.resolution).max().unwrap_or(1);
        AtlasLayout { cells, cell }
    }

    pub fn size(&self) -> u32 {
        self.cells * self.cell
    }

    /// The texel origin of tile `i`.
    pub fn origin(&self, i: usize) -> (u32, u32) {
        let i = i as u32;
        ((i % self.cells) * self.cell, (i / self.cells) * self.cell)
    }
}

/// A direction perpendicular enough to `d` to be a view's up vector.
fn up_for(d: Vec3) -> Vec3 {
    if d.y.abs() > 0.99 {
        Vec3::Z
    } else {
        Vec3::Y
    }
}

/// The light's clip-from-world matrix, whether it is a perspective one, and the world size of one
/// texel of a `resolution`-texel map (per unit of distance from the light for perspective).
pub fn light_projection(light: &Light, bounds: &Bounds, resolution: u32) -> (Mat4, bool, f32) {
    let d = light.direction.normalize_or(Vec3::NEG_Y);
    let center = (bounds.min + bounds.max) * 0.5;
    let radius = ((bounds.max - bounds.min).length() * 0.5).max(1e-3);
    let res = resolution.max(1) as f32;
    match light.kind {
        LightKind::Spot { outer_cone, .. } => {
            // The cone, with a margin so the PCF taps at its edge stay inside the map.
            let fov = (2.0 * outer_cone + 4f32.to_radians())
                .clamp(1f32.to_radians(), 170f32.to_radians());
            let view = Mat4::look_at_rh(light.position, light.position + d, up_for(d));
            let near = (radius * 1e-3).max(1e-3);
            let proj = Mat4::perspective_infinite_reverse_rh(fov, 1.0, near);
            (proj * view, true, 2.0 * (fov * 0.5).tan() / res)
        }
        _ => {
            let eye = center - d * (2.0 * radius);
            let view = Mat4::look_at_rh(eye, center, up_for(d));
            let mut lo = Vec3::splat(f32::INFINITY);
            let mut hi = Vec3::splat(f32::NEG_INFINITY);
            for i in 0..8 {
                let corner = Vec3::new(
                    if i & 1 == 0 {
                        bounds.min.x
                    } else {
                        bounds.max.x
                    },
                    if i & 2 == 0 {
                        bounds.min.y
                    } else {
                        bounds.max.y
                    },
                    if i & 4 == 0 {
                        bounds.min.z
                    } else {
                        bounds.max.z
                    },
                );
                let v = view.transform_point3(corner);
                lo = lo.min(v);
                hi = hi.max(v);
            }
            // Square texels: the larger extent on both axes, centred.
            let extent = (hi.x - lo.x).max(hi.y - lo.y).max(1e-3) * 1.02;
            let (cx, cy) = ((lo.x + hi.x) * 0.5, (lo.y + hi.y) * 0.5);
            let margin = 0.01 * radius;
            // View space looks down -z: the nearest point has the largest z. Near and far
            // swapped give reversed-Z (nearest 1, farthest 0).
            let (near, far) = (-hi.z - margin, -lo.z + margin);
            let proj = Mat4::orthographic_rh(
                cx - extent * 0.5,
                cx + extent * 0.5,
                cy - extent * 0.5,
                cy + extent * 0.5,
                far,
                near,
            );
            (proj * view, false, extent / res)
        }
    }
}

/// The GPU record of each planned shadow map, in plan order.
pub fn shadow_records(
    shadows: &[ShadowPlan],
    lights: &[Light],
    bounds: &Bounds,
    atlas: &AtlasLayout,
) -> Vec<(GpuShadow, Mat4)> {
    let size = atlas.size() as f32;
    shadows
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let (m, perspective, texel_world) =
                light_projection(&lights[s.light], bounds, s.resolution);
            let (x, y) = atlas.origin(i);
            let record = GpuShadow {
                clip_from_world: m.to_cols_array_2d(),
                tile: [
                    x as f32 / size,
                    y as f32 / size,
                    s.resolution as f32 / size,
                    s.resolution as f32 / size,
                ],
                params: [
                    // The look-up point moves off the surface by the bias plus the PCF radius:
                    // a tap `r` texels away on a receiver sloped to the light sits up to about
                    // `r` texels' depth lower, and would shadow the surface itself (acne).
                    (s.bias + s.filter_radius + 1.0) * texel_world,
                    perspective as u32 as f32,
                    s.filter_radius,
                    1.0 / size,
                ],
            };
            (record, m)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn light(kind: LightKind, position: Vec3, direction: Vec3) -> Light {
        Light {
            name: "l".into(),
            kind,
            color: [1.0; 3],
            intensity: 1.0,
            range: None,
            position,
            direction,
            shadow: None,
        }
    }

    #[test]
    fn directional_projection_puts_the_scene_inside_reversed_z() {
        let bounds = Bounds {
            min: Vec3::new(-2.0, 0.0, -1.0),
            max: Vec3::new(2.0, 1.0, 1.0),
        };
        let l = light(
            LightKind::Directional,
            Vec3::ZERO,
            Vec3::new(0.3, -1.0, 0.2),
        );
        let (m, perspective, _) = light_projection(&l, &bounds, 1024);
        assert!(!perspective);
        let top = m.project_point3(Vec3::new(0.0, 1.0, 0.0));
        let bottom = m.project_point3(Vec3::new(0.0, 0.0, 0.0));
        for p in [top, bottom] {
            assert!(
                p.x.abs() <= 1.0 && p.y.abs() <= 1.0 && (0.0..=1.0).contains(&p.z),
                "{p}"
            );
        }
        // Nearer the light (higher) is the larger depth.
        assert!(top.z > bottom.z, "{top} {bottom}");
    }

    #[test]
    fn spot_projection_sees_along_its_axis() {
        let bounds = Bounds {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        };
        let l = light(
            LightKind::Spot {
                inner_cone: 0.3,
                outer_cone: 0.5,
            },
            Vec3::new(0.0, 3.0, 0.0),
            Vec3::NEG_Y,
        );
        let (m, perspective, _) = light_projection(&l, &bounds, 512);
        assert!(perspective);
        let near = m.project_point3(Vec3::new(0.0, 1.0, 0.0));
        let far = m.project_point3(Vec3::new(0.0, 0.0, 0.0));
        assert!(near.x.abs() < 1e-5 && near.y.abs() < 1e-5);
        assert!(near.z > far.z && far.z > 0.0 && near.z <= 1.0);
    }

    #[test]
    fn atlas_tiles_do_not_overlap() {
        let plan = |r: u32| ShadowPlan {
            light: 0,
            name: String::new(),
            resolution: r,
            filter_radius: 1.0,
            bias: 1.0,
        };
        let shadows = vec![plan(512), plan(1024), plan(256)];
        let a = AtlasLayout::new(&shadows);
        assert_eq!((a.cells, a.cell, a.size()), (2, 1024, 2048));
        assert_eq!(a.origin(0), (0, 0));
        assert_eq!(a.origin(1), (1024, 0));
        assert_eq!(a.origin(2), (0, 1024));
    }
}
