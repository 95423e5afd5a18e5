//! Completing a mesh's shading frame: normals when the file has none, MikkTSpace tangents when it
//! has none, and repair of zero-length or non-finite normals and tangents, so the G-buffer never
//! receives NaN.

use std::collections::HashMap;

use glam::{Vec3, Vec4};

use super::Vertex;

/// Area-weighted sum of the face normals around each vertex (not normalised; zero for a vertex
/// that only touches degenerate triangles).
pub(super) fn face_normal_sums(vertices: &[Vertex], indices: &[u32]) -> Vec<Vec3> {
    let mut sums = vec![Vec3::ZERO; vertices.len()];
    for tri in indices.chunks_exact(3) {
        let [a, b, c] = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
        let pa = Vec3::from(vertices[a].position);
        let pb = Vec3::from(vertices[b].position);
        let pc = Vec3::from(vertices[c].position);
        // The cross product's length is twice the triangle's area: larger faces weigh more.
        let n = (pb - pa).cross(pc - pa);
        if n.is_finite() {
            for &v in &[a, b, c] {
                sums[v] += n;
            }
        }
    }
    sums
}

/// Gives every vertex the normalised sum of its faces' normals: smooth where triangles share
/// vertices, flat where they do not.
pub(super) fn generate_normals(vertices: &mut [Vertex], indices: &[u32]) {
    let sums = face_normal_sums(vertices, indices);
    for (v, n) in vertices.iter_mut().zip(sums) {
        v.normal = n.normalize_or_zero().to_array();
    }
}

/// Replaces zero-length or non-finite normals (by the faces' normal, or +Y where the faces are
/// degenerate too) and normalises the rest. Returns how many were replaced.
pub(super) fn repair_normals(vertices: &mut [Vertex], indices: &[u32]) -> usize {
    let is_bad = |n: Vec3| !n.is_finite() || n.length_squared() < 1e-12;
    if !vertices.iter().any(|v| is_bad(Vec3::from(v.normal))) {
        for v in vertices.iter_mut() {
            v.normal = Vec3::from(v.normal).normalize().to_array();
        }
        return 0;
    }
    let sums = face_normal_sums(vertices, indices);
    let mut repaired = 0;
    for (v, sum) in vertices.iter_mut().zip(sums) {
        let n = Vec3::from(v.normal);
        v.normal = if is_bad(n) {
            repaired += 1;
            sum.try_normalize().unwrap_or(Vec3::Y).to_array()
        } else {
            n.normalize().to_array()
        };
    }
    repaired
}

/// A unit vector perpendicular to the unit vector `n` (Duff et al. 2017, "Building an orthonormal
/// basis, revisited"): continuous except across n.z = 0's sign change, and never degenerate.
pub(super) fn any_perpendicular(n: Vec3) -> Vec3 {
    let sign = 1f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x)
}

/// Makes every tangent unit length and orthogonal to its (unit) normal, with w = +1 or -1.
/// Tangents that are zero, non-finite or parallel to the normal get an arbitrary perpendicular
/// direction. Returns how many were replaced.
pub(super) fn repair_tangents(vertices: &mut [Vertex]) -> usize {
    let mut repaired = 0;
    for v in vertices.iter_mut() {
        let n = Vec3::from(v.normal);
        let t4 = Vec4::from(v.tangent);
        let t = t4.truncate();
        let w = if t4.w < 0.0 { -1.0 } else { 1.0 };
        // A tangent (nearly) parallel to the normal leaves no usable direction in the surface.
        let residual = t - n * n.dot(t);
        let t = if t.is_finite() && residual.length() > 1e-3 * t.length() {
            // Gram-Schmidt of a nearly parallel tangent loses precision: a second pass restores it.
            let t = residual.normalize();
            (t - n * n.dot(t)).normalize()
        } else {
            repaired += 1;
            any_perpendicular(n)
        };
        v.tangent = [t.x, t.y, t.z, w];
    }
    repaired
}

/// Gives every vertex the arbitrary tangent `any_perpendicular(normal)` with w = +1 (for meshes
/// without texture coordinates, where no tangent is more right than another).
pub(super) fn arbitrary_tangents(vertices: &mut [Vertex]) {
    for v in vertices.iter_mut() {
        let t = any_perpendicular(Vec3::from(v.normal));
        v.tangent = [t.x, t.y, t.z, 1.0];
    }
}

/// MikkTSpace tangents (the convention normal maps are baked in). MikkTSpace works per triangle
/// corner; where two corners sharing a vertex get different tangents (mirrored UVs, for example)
/// the vertex is split. Returns false if MikkTSpace could not run (the caller then falls back to
/// arbitrary tangents).
pub(super) fn mikktspace_tangents(vertices: &mut Vec<Vertex>, indices: &mut [u32]) -> bool {
    struct Corners<'a> {
        vertices: &'a [Vertex],
        indices: &'a [u32],
        tangents: Vec<Option<[f32; 4]>>,
    }
    impl mikktspace::Geometry for Corners<'_> {
        fn num_faces(&self) -> usize {
            self.indices.len() / 3
        }
        fn num_vertices_of_face(&self, _face: usize) -> usize {
            3
        }
        fn position(&self, face: usize, vert: usize) -> [f32; 3] {
            self.vertices[self.indices[face * 3 + vert] as usize].position
        }
        fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
            self.vertices[self.indices[face * 3 + vert] as usize].normal
        }
        fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
            self.vertices[self.indices[face * 3 + vert] as usize].uv
        }
        fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, vert: usize) {
            if let Some(slot) = self.tangents.get_mut(face * 3 + vert) {
                *slot = Some(tangent);
            }
        }
    }

    if indices.len() < 3 {
        return false;
    }
    let mut corners =
        Corners { vertices: vertices.as_slice(), indices: &*indices, tangents: vec![None; indices.len()] };
    if !mikktspace::generate_tangents(&mut corners) {
        return false;
    }
    let tangents = corners.tangents;

    let close =
        |a: [f32; 4], b: [f32; 4]| a[3].signum() == b[3].signum() && (0..3).all(|k| (a[k] - b[k]).abs() <= 1e-4);
    let mut assigned: Vec<Option<[f32; 4]>> = vec![None; vertices.len()];
    // The extra copies made of each split vertex.
    let mut copies: HashMap<u32, Vec<u32>> = HashMap::new();
    for (corner, index) in indices.iter_mut().enumerate() {
        // MikkTSpace skips degenerate triangles; their corners keep whatever the vertex gets.
        let Some(t) = tangents[corner] else { continue };
        let v = *index as usize;
        match assigned[v] {
            None => {
                assigned[v] = Some(t);
                vertices[v].tangent = t;
            }
            Some(existing) if close(existing, t) => {}
            Some(_) => {
                let found = copies
                    .get(index)
                    .and_then(|c| c.iter().copied().find(|&copy| close(vertices[copy as usize].tangent, t)));
                *index = match found {
                    Some(copy) => copy,
                    None => {
                        let mut split = vertices[v];
                        split.tangent = t;
                        vertices.push(split);
                        let copy = (vertices.len() - 1) as u32;
                        copies.entry(*index).or_default().push(copy);
                        copy
                    }
                };
            }
        }
    }
    // Vertices that no usable triangle reaches: any frame will do, nobody sees them.
    for (v, t) in vertices.iter_mut().zip(&assigned) {
        if t.is_none() {
            let t = any_perpendicular(Vec3::from(v.normal));
            v.tangent = [t.x, t.y, t.z, 1.0];
        }
    }
    true
}

/// Applies a KHR_texture_transform (offset, rotation, scale) to texture coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct UvTransform {
    pub offset: [f32; 2],
    pub rotation: f32,
    pub scale: [f32; 2],
}

impl UvTransform {
    pub const IDENTITY: UvTransform = UvTransform { offset: [0.0, 0.0], rotation: 0.0, scale: [1.0, 1.0] };

    /// uv' = T * R * S * uv, with R as the extension defines it (counter-clockwise in UV space,
    /// which is clockwise on the image because v points down).
    pub fn apply(&self, uv: [f32; 2]) -> [f32; 2] {
        let (s, c) = self.rotation.sin_cos();
        let x = uv[0] * self.scale[0];
        let y = uv[1] * self.scale[1];
        [c * x + s * y + self.offset[0], -s * x + c * y + self.offset[1]]
    }

    /// Whether the transform changes the direction of +u or the handedness of the UV frame, which
    /// tangents stored in the file do not know about.
    pub fn turns_or_mirrors(&self) -> bool {
        self.rotation != 0.0 || self.scale[0] < 0.0 || self.scale[1] < 0.0
    }
}
