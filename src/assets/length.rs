//! Lengths with units and a material's UV density (world length per UV unit).

use crate::scene::Scene;
use crate::{Error, Result};

/// A length with its unit (`0.8mm`, `1 cm`, `0.01m`, `0.03in`), in metres.
pub fn parse_length(text: &str) -> Result<f64> {
    let t = text.trim();
    // The unit is the trailing letters, so that 1e-3m keeps its exponent.
    let number = t.trim_end_matches(|c: char| c.is_ascii_alphabetic());
    let (number, unit) = (number.trim(), &t[number.len()..]);
    let scale = match unit {
        "mm" => 1e-3,
        "cm" => 1e-2,
        "m" => 1.0,
        "in" => 0.0254,
        "" => {
            return Err(Error::input(format!(
                "pitch '{text}' has no unit; write it with one of mm, cm, m, in (e.g. 0.8mm): glTF lengths are metres, and a bare number is too easy to get wrong"
            )))
        }
        other => {
            return Err(Error::input(format!(
                "pitch '{text}' has the unit '{other}', which weft does not know; use mm, cm, m or in (e.g. 0.8mm)"
            )))
        }
    };
    let x: f64 = number.parse().map_err(|_| {
        Error::input(format!(
            "pitch '{text}': '{number}' is not a number; write e.g. 0.8mm"
        ))
    })?;
    if !(x.is_finite() && x > 0.0) {
        return Err(Error::input(format!(
            "pitch '{text}' must be a positive length (e.g. 0.8mm)"
        )));
    }
    Ok(x * scale)
}

/// A length in metres, in the unit that reads best.
pub fn format_length(m: f64) -> String {
    if m < 1e-2 {
        format!("{:.3} mm", m * 1e3)
    } else if m < 1.0 {
        format!("{:.2} cm", m * 1e2)
    } else {
        format!("{m:.3} m")
    }
}

/// How texture space maps to the world on a material's triangles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvDensity {
    /// World length per UV unit (metres), `sqrt(world area / UV area)` over all its triangles.
    pub metres_per_uv: f64,
    /// The same per drawn primitive: the smallest and largest (they differ when parts of the
    /// mesh are unwrapped at different scales).
    pub min: f64,
    pub max: f64,
    /// Drawn primitives (mesh primitive × node) that use the material.
    pub primitives: usize,
}

/// The UV density of material `material` in a loaded scene. `who` names it in messages.
pub fn uv_density(scene: &Scene, material: usize, who: &str) -> Result<UvDensity> {
    let (mut world, mut uv) = (0f64, 0f64);
    let (mut min, mut max, mut primitives) = (f64::INFINITY, 0f64, 0usize);
    for draw in &scene.draws {
        let Some(mesh) = scene.meshes.get(draw.mesh) else {
            continue;
        };
        if mesh.material != material || mesh.topology != crate::scene::Topology::Triangles {
            continue;
        }
        let (mut w, mut t) = (0f64, 0f64);
        for tri in mesh.indices.chunks_exact(3) {
            let v: Option<Vec<_>> = tri.iter().map(|&i| mesh.vertices.get(i as usize)).collect();
            let Some(v) = v else { continue };
            let p: Vec<glam::DVec3> = v
                .iter()
                .map(|v| {
                    draw.world
                        .as_dmat4()
                        .transform_point3(glam::Vec3::from(v.position).as_dvec3())
                })
                .collect();
            let a = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
            let q: Vec<glam::DVec2> = v
                .iter()
                .map(|v| glam::Vec2::from(v.uv).as_dvec2())
                .collect();
            let b = 0.5 * (q[1] - q[0]).perp_dot(q[2] - q[0]).abs();
            if a.is_finite() && b.is_finite() {
                w += a;
                t += b;
            }
        }
        primitives += 1;
        if t > 0.0 && w > 0.0 {
            let d = (w / t).sqrt();
            min = min.min(d);
            max = max.max(d);
        }
        world += w;
        uv += t;
    }
    if primitives == 0 {
        return Err(Error::input(format!(
            "{who} is not used by any triangle the scene draws, so there is no mesh to measure the thread pitch on; choose a material that a node's mesh uses"
        )));
    }
    if !(uv > 0.0 && world > 0.0) {
        return Err(Error::input(format!(
            "{who}: its triangles have no usable texture coordinates (TEXCOORD_0 missing, or every UV triangle has zero area), and the weave is laid out in UV space; unwrap the mesh (add UVs) and export again"
        )));
    }
    Ok(UvDensity {
        metres_per_uv: (world / uv).sqrt(),
        min,
        max,
        primitives,
    })
}
