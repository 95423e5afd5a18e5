//! What the renderer assumes of every scene the loader returns: indices in range, finite positions,
//! unit normals and tangents (orthogonal, w = +-1), finite UVs and transforms, valid material and
//! texture references, texture sizes that match their pixels. Shared by the fuzz target and by
//! tests/fuzz_corpus.rs and tests/fuzz_mutate.rs (through `#[path]`), so all three check the same.

#![allow(dead_code)]

use weft::scene::Scene;

fn unit(v: [f32; 3]) -> bool {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    (l - 1.0).abs() < 1e-3
}

pub fn check(s: &Scene) -> Result<(), String> {
    for m in &s.meshes {
        let who = &m.name;
        if m.material >= s.materials.len() {
            return Err(format!(
                "mesh '{who}': material {} of {}",
                m.material,
                s.materials.len()
            ));
        }
        // Whole primitives: triangles, segments or points.
        if m.indices.len() % m.topology.arity() != 0 || m.indices.is_empty() {
            return Err(format!(
                "mesh '{who}': {} indices for {:?}",
                m.indices.len(),
                m.topology
            ));
        }
        if let Some(i) = m.indices.iter().find(|&&i| i as usize >= m.vertices.len()) {
            return Err(format!(
                "mesh '{who}': index {i} of {} vertices",
                m.vertices.len()
            ));
        }
        for (k, v) in m.vertices.iter().enumerate() {
            let t = [v.tangent[0], v.tangent[1], v.tangent[2]];
            let dot = v.normal[0] * t[0] + v.normal[1] * t[1] + v.normal[2] * t[2];
            let ok = v.position.iter().all(|c| c.is_finite())
                && v.uv.iter().all(|c| c.is_finite())
                && unit(v.normal)
                && unit(t)
                && dot.abs() < 1e-3
                && (v.tangent[3] == 1.0 || v.tangent[3] == -1.0);
            if !ok {
                return Err(format!("mesh '{who}' vertex {k}: {v:?}"));
            }
        }
    }
    for d in &s.draws {
        if d.mesh >= s.meshes.len() || !d.world.is_finite() {
            return Err(format!("draw of mesh {} with world {:?}", d.mesh, d.world));
        }
    }
    for m in &s.materials {
        let textures = [
            m.base_color_texture,
            m.metallic_roughness_texture,
            m.normal_texture,
            m.emissive_texture,
        ];
        if textures.iter().flatten().any(|&t| t >= s.textures.len()) {
            return Err(format!(
                "material '{}' uses a texture that does not exist",
                m.name
            ));
        }
        let numbers = m.base_color.iter().chain(&m.emissive).chain([
            &m.metallic,
            &m.roughness,
            &m.normal_scale,
        ]);
        if !numbers.into_iter().all(|c| c.is_finite()) {
            return Err(format!("material '{}' has a non-finite factor", m.name));
        }
    }
    for t in &s.textures {
        if t.rgba8.len() as u64 != u64::from(t.width) * u64::from(t.height) * 4
            || t.width == 0
            || t.height == 0
        {
            return Err(format!(
                "texture '{}' is {}x{} with {} bytes",
                t.name,
                t.width,
                t.height,
                t.rgba8.len()
            ));
        }
    }
    for l in &s.lights {
        if !unit(l.direction.to_array()) || !l.position.is_finite() || !l.intensity.is_finite() {
            return Err(format!(
                "light '{}' at {} towards {}",
                l.name, l.position, l.direction
            ));
        }
    }
    for c in &s.cameras {
        // A perspective camera needs znear > 0; an orthographic one (glTF) znear >= 0 and a
        // finite zfar beyond it.
        let near_ok = match c.orthographic {
            None => c.znear > 0.0,
            Some(_) => c.znear >= 0.0 && c.zfar.is_some_and(|f| f.is_finite() && f > c.znear),
        };
        if !c.view.is_finite() || !(c.yfov > 0.0 && c.yfov < std::f32::consts::PI) || !near_ok {
            return Err(format!(
                "camera '{}' with view {:?}, yfov {}, znear {}",
                c.name, c.view, c.yfov, c.znear
            ));
        }
    }
    Ok(())
}
