//! Completing a mesh's shading frame: normals when the file has none, MikkTSpace tangents when it
//! has none, and repair of zero-length or non-finite normals and tangents, so the G-buffer never
//! receives NaN.

use std::collections::HashMap;

use glam::{Vec3, Vec4};

use super::animation::MorphTarget;
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

/// `v` scaled to unit length without overflow or underflow on the way (a normal of (1e30, 0, 0)
/// is +X; `normalize` would square 1e30 to infinity and return zero); None for a zero-length or
/// non-finite `v`.
pub(super) fn direction(v: Vec3) -> Option<Vec3> {
    let largest = v.abs().max_element();
    if !(largest.is_finite() && largest > 0.0) {
        return None;
    }
    (v / largest).try_normalize()
}

/// What [`flat_normals`] did besides the vertices.
pub(super) struct Flat {
    /// For each new vertex, the vertex it copies (for the per-vertex data that travels with it:
    /// colours, joints, morph deltas).
    pub origin: Vec<usize>,
    /// Triangles with no area (their corners get +Y; such a triangle covers no pixel).
    pub degenerate: usize,
    /// For each morph target that moves positions but gives no normal deltas (its index), the
    /// deltas per new vertex that turn each face's rest normal into its morphed one.
    pub target_normals: Vec<(usize, Vec<[f32; 3]>)>,
}

/// Flat normals for a primitive the file gives none (glTF 2.0 §3.7.2.1): each triangle's corners
/// get its face normal. A vertex is shared only by triangles whose normals agree at rest and in
/// every morph target that moves it (within 1e-6 of the cosine, 0.08°); elsewhere it is copied,
/// so a flat grid keeps one vertex per grid point and a cube's corner becomes three. Rewrites
/// `indices` to the new vertices, which it returns; a vertex no triangle uses is left out.
pub(super) fn flat_normals(
    vertices: &[Vertex],
    indices: &mut [u32],
    targets: &[MorphTarget],
) -> (Vec<Vertex>, Flat) {
    const NONE: u32 = u32::MAX;
    const MAX_SEARCHED: usize = 64;
    let face = |p: [Vec3; 3]| direction((p[1] - p[0]).cross(p[2] - p[0]));
    // A face degenerate in a target is ZERO there, and agrees only with another such face.
    let same = |a: &Vec3, b: &Vec3| {
        if *a == Vec3::ZERO || *b == Vec3::ZERO {
            a == b
        } else {
            a.dot(*b) > 1.0 - 1e-6
        }
    };
    let moved: Vec<usize> = (0..targets.len())
        .filter(|&t| targets[t].normals.is_empty() && targets[t].positions.len() == vertices.len())
        .collect();
    let stride = 1 + moved.len();
    // Per original vertex its newest copy, per copy the one before it: the copies of a vertex
    // as a list; per copy its normals at rest and in each moved target (`stride` of them).
    let mut first = vec![NONE; vertices.len()];
    let mut next: Vec<u32> = Vec::new();
    let mut normals: Vec<Vec3> = Vec::new();
    let mut out: Vec<Vertex> = Vec::with_capacity(vertices.len());
    let mut origin = Vec::with_capacity(vertices.len());
    let mut sig = Vec::with_capacity(stride);
    let mut degenerate = 0;
    for tri in indices.chunks_exact_mut(3) {
        let p = [0, 1, 2].map(|c| Vec3::from(vertices[tri[c] as usize].position));
        let n = face(p);
        degenerate += usize::from(n.is_none());
        let n = n.unwrap_or(Vec3::Y);
        sig.clear();
        sig.push(n);
        for &t in &moved {
            let d = &targets[t].positions;
            let q = [0, 1, 2].map(|c| p[c] + Vec3::from(d[tri[c] as usize]));
            sig.push(face(q).unwrap_or(Vec3::ZERO));
        }
        for corner in tri.iter_mut() {
            let v = *corner as usize;
            let mut j = first[v];
            // Only the newest copies are searched: a cone's apex shared by a million faces would
            // otherwise cost a million comparisons a corner. Past them a corner gets a copy of its
            // own, with the same normal as one it missed at worst: a vertex more, nothing seen.
            let mut searched = 0;
            while j != NONE && searched < MAX_SEARCHED {
                let theirs = &normals[j as usize * stride..][..stride];
                if theirs.iter().zip(&sig).all(|(a, b)| same(a, b)) {
                    break;
                }
                j = next[j as usize];
                searched += 1;
            }
            if searched == MAX_SEARCHED {
                j = NONE;
            }
            if j == NONE {
                j = out.len() as u32;
                let mut copy = vertices[v];
                copy.normal = n.to_array();
                out.push(copy);
                origin.push(v);
                next.push(first[v]);
                first[v] = j;
                normals.extend_from_slice(&sig);
            }
            *corner = j;
        }
    }
    let target_normals = moved
        .iter()
        .enumerate()
        .map(|(m, &t)| {
            let deltas = (0..out.len())
                .map(|j| {
                    let morphed = normals[j * stride + 1 + m];
                    if morphed == Vec3::ZERO {
                        [0.0; 3]
                    } else {
                        (morphed - normals[j * stride]).to_array()
                    }
                })
                .collect();
            (t, deltas)
        })
        .collect();
    (
        out,
        Flat {
            origin,
            degenerate,
            target_normals,
        },
    )
}

/// Replaces zero-length or non-finite normals (by the faces' normal, or +Y where the faces are
/// degenerate too) and normalises the rest. Returns how many were replaced.
pub(super) fn repair_normals(vertices: &mut [Vertex], indices: &[u32]) -> usize {
    // Shorter than 1e-6 (compared without squaring, which underflows or overflows).
    let is_bad = |n: Vec3| direction(n).is_none_or(|d| n.dot(d) < 1e-6);
    if !vertices.iter().any(|v| is_bad(Vec3::from(v.normal))) {
        for v in vertices.iter_mut() {
            v.normal = direction(Vec3::from(v.normal))
                .unwrap_or(Vec3::Y)
                .to_array();
        }
        return 0;
    }
    let sums = face_normal_sums(vertices, indices);
    let mut repaired = 0;
    for (v, sum) in vertices.iter_mut().zip(sums) {
        let n = Vec3::from(v.normal);
        v.normal = if is_bad(n) {
            repaired += 1;
            direction(sum).unwrap_or(Vec3::Y).to_array()
        } else {
            direction(n).unwrap_or(Vec3::Y).to_array()
        };
    }
    repaired
}

/// A unit vector perpendicular to the unit vector `n` (Duff et al. 2017, "Building an orthonormal
/// basis, revisited"): continuous except across n.z = 0's sign change, and never degenerate.
/// The same formula and sign rule (n.z = -0.0 counts as positive) as `any_perpendicular` of
/// glsl/include/fabric.glsl and its twin in `reference::brdf`; this copy repairs meshes at load,
/// a layer below the reference (src/lib.rs), in glam's types.
pub(super) fn any_perpendicular(n: Vec3) -> Vec3 {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
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
        let w = if t4.w < 0.0 { -1.0 } else { 1.0 };
        // Unit length first, so huge or tiny tangents do not overflow or underflow below.
        let t = direction(t4.truncate()).unwrap_or(Vec3::ZERO);
        // A tangent (nearly) parallel to the normal leaves no usable direction in the surface.
        let residual = t - n * n.dot(t);
        let t = if residual.length() > 1e-3 {
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

/// MikkTSpace tangents (the convention normal maps are baked in), by `bevy_mikktspace` (safe
/// Rust, output identical to the C reference). MikkTSpace works per triangle corner; where two
/// corners sharing a vertex get different tangents (mirrored UVs, for example) the vertex is
/// split. Degenerate triangles (coincident corners, zero UV area), collapsed meshes and
/// positions whose extent overflows f32 are MikkTSpace's to handle: it gives a corner no tangent
/// where it has none, and such corners keep whatever their vertex gets. Returns false if no
/// triangle got a tangent (the caller then falls back to arbitrary tangents). `uv_of` gives the
/// texture coordinates the tangents follow: glTF's are those of the normal texture (its set,
/// through its transform).
pub(super) fn mikktspace_tangents(
    vertices: &mut Vec<Vertex>,
    indices: &mut [u32],
    uv_of: &dyn Fn(&Vertex) -> [f32; 2],
) -> bool {
    /// The triangles MikkTSpace sees: `faces` lists the mesh's triangles whose indices are in
    /// range (the loader has checked them; this keeps the function total on its own).
    struct Corners<'a> {
        vertices: &'a [Vertex],
        indices: &'a [u32],
        faces: &'a [usize],
        uv_of: &'a dyn Fn(&Vertex) -> [f32; 2],
        /// Per corner of the mesh (not of `faces`).
        tangents: Vec<Option<[f32; 4]>>,
    }
    impl Corners<'_> {
        fn vertex(&self, face: usize, vert: usize) -> &Vertex {
            &self.vertices[self.indices[self.faces[face] * 3 + vert] as usize]
        }
    }
    impl bevy_mikktspace::Geometry for Corners<'_> {
        fn num_faces(&self) -> usize {
            self.faces.len()
        }
        fn num_vertices_of_face(&self, _face: usize) -> usize {
            3
        }
        fn position(&self, face: usize, vert: usize) -> [f32; 3] {
            self.vertex(face, vert).position
        }
        fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
            self.vertex(face, vert).normal
        }
        fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
            // MikkTSpace's bitangent follows +v with v up (Blender's UVs, where normal maps are
            // baked); glTF's v goes down the image, and its normal maps' +Y is up the image: the
            // UV is given as (u, 1 - v), as Blender's glTF exporter does, so that the generated
            // tangents' sign agrees with the ones such files carry (NormalTangentTest without its
            // tangents renders as NormalTangentMirrorTest with them).
            let [u, v] = (self.uv_of)(self.vertex(face, vert));
            [u, 1.0 - v]
        }
        fn set_tangent(
            &mut self,
            tangent: Option<bevy_mikktspace::TangentSpace>,
            face: usize,
            vert: usize,
        ) {
            let corner = self.faces.get(face).map(|f| f * 3 + vert);
            if let Some(slot) = corner.and_then(|c| self.tangents.get_mut(c)) {
                *slot = tangent.map(|t| t.tangent_encoded());
            }
        }
    }

    let in_range = |corner: usize| (indices[corner] as usize) < vertices.len();
    let faces: Vec<usize> = (0..indices.len() / 3)
        .filter(|&t| (3 * t..3 * t + 3).all(in_range))
        .collect();
    let mut corners = Corners {
        vertices: vertices.as_slice(),
        indices: &*indices,
        faces: &faces,
        uv_of,
        tangents: vec![None; indices.len()],
    };
    // The error type has no variants yet (`non_exhaustive`): a future one means "no tangents".
    if bevy_mikktspace::generate_tangents(&mut corners).is_err() {
        return false;
    }
    let tangents = corners.tangents;
    if tangents.iter().all(Option::is_none) {
        return false;
    }

    let close = |a: [f32; 4], b: [f32; 4]| {
        a[3].signum() == b[3].signum() && (0..3).all(|k| (a[k] - b[k]).abs() <= 1e-4)
    };
    let mut assigned: Vec<Option<[f32; 4]>> = vec![None; vertices.len()];
    // The extra copies made of each split vertex.
    let mut copies: HashMap<u32, Vec<u32>> = HashMap::new();
    for (corner, index) in indices.iter_mut().enumerate() {
        // Corners MikkTSpace gave no tangent keep whatever the vertex gets.
        let Some(t) = tangents[corner] else { continue };
        let v = *index as usize;
        match assigned[v] {
            None => {
                assigned[v] = Some(t);
                vertices[v].tangent = t;
            }
            Some(existing) if close(existing, t) => {}
            Some(_) => {
                let found = copies.get(index).and_then(|c| {
                    c.iter()
                        .copied()
                        .find(|&copy| close(vertices[copy as usize].tangent, t))
                });
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
    pub const IDENTITY: UvTransform = UvTransform {
        offset: [0.0, 0.0],
        rotation: 0.0,
        scale: [1.0, 1.0],
    };

    /// uv' = T * R * S * uv, with R as the extension defines it (counter-clockwise in UV space,
    /// which is clockwise on the image because v points down).
    pub fn apply(&self, uv: [f32; 2]) -> [f32; 2] {
        let (s, c) = self.rotation.sin_cos();
        let x = uv[0] * self.scale[0];
        let y = uv[1] * self.scale[1];
        [
            c * x + s * y + self.offset[0],
            -s * x + c * y + self.offset[1],
        ]
    }

    /// The transform as an affine map, rows `[a, b, c]`: u' = a·u + b·v + c (what [`apply`] does).
    ///
    /// [`apply`]: UvTransform::apply
    pub fn affine(&self) -> [[f32; 3]; 2] {
        let (s, c) = self.rotation.sin_cos();
        [
            [c * self.scale[0], s * self.scale[1], self.offset[0]],
            [-s * self.scale[0], c * self.scale[1], self.offset[1]],
        ]
    }

    /// The inverse affine map; None when the transform is singular (a zero scale).
    pub fn inverse(&self) -> Option<[[f32; 3]; 2]> {
        let [[a, b, c], [d, e, f]] = self.affine();
        let det = a * e - b * d;
        if !(det.abs() > 1e-12) || !det.is_finite() {
            return None;
        }
        let (ia, ib, id, ie) = (e / det, -b / det, -d / det, a / det);
        Some([[ia, ib, -(ia * c + ib * f)], [id, ie, -(id * c + ie * f)]])
    }

    /// `outer ∘ inner` of two affine maps.
    pub fn compose(outer: [[f32; 3]; 2], inner: [[f32; 3]; 2]) -> [[f32; 3]; 2] {
        let [[a, b, c], [d, e, f]] = outer;
        let [[p, q, r], [s, t, u]] = inner;
        [
            [a * p + b * s, a * q + b * t, a * r + b * u + c],
            [d * p + e * s, d * q + e * t, d * r + e * u + f],
        ]
    }

    /// Whether the transform changes the direction of +u or the handedness of the UV frame, which
    /// tangents stored in the file do not know about.
    pub fn turns_or_mirrors(&self) -> bool {
        self.rotation != 0.0 || self.scale[0] < 0.0 || self.scale[1] < 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vertex(position: [f32; 3], uv: [f32; 2]) -> Vertex {
        Vertex {
            position,
            normal: [0.0, 0.0, 1.0],
            tangent: [0.0; 4],
            uv,
            uv1: [0.0; 2],
        }
    }

    #[test]
    fn flat_normals_split_only_where_faces_disagree_and_follow_morph_targets() {
        // A flat quad (two triangles sharing an edge, normal +Z), a third triangle folded up
        // along the quad's edge x = 1 (normal +X) and a degenerate one.
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 0.0, 1.0],
            [2.0, 2.0, 2.0],
        ];
        let v: Vec<Vertex> = p.iter().map(|&p| vertex(p, [0.0; 2])).collect();
        let mut indices = vec![0, 1, 2, 0, 2, 3, 1, 2, 4, 0, 5, 5];
        let (out, flat) = flat_normals(&v, &mut indices, &[]);
        assert_eq!(flat.degenerate, 1);
        // The quad's four corners shared; the fold's 1 and 2 copied, 4 its own; 0 and 5 for
        // the degenerate triangle (+Y, unlike the quad's 0).
        assert_eq!(out.len(), 4 + 3 + 2);
        assert_eq!(&indices[..6], &[0, 1, 2, 0, 2, 3]);
        for (k, tri) in indices.chunks_exact(3).enumerate() {
            let want = [
                [0.0, 0.0, 1.0],
                [0.0, 0.0, 1.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
            ][k];
            for &i in tri {
                assert_eq!(out[i as usize].normal, want, "triangle {k}");
                assert_eq!(out[i as usize].position, p[flat.origin[i as usize]]);
            }
        }

        // A target lifting corner 3 to z = 1 tilts the quad's second triangle to (1, -1, 1)/sqrt 3
        // and leaves the first flat: the shared corners 0 and 2 split between them.
        let mut lifted = vec![[0.0; 3]; 6];
        lifted[3] = [0.0, 0.0, 1.0];
        let targets = [
            MorphTarget {
                positions: lifted,
                ..MorphTarget::default()
            },
            // A target with its own normal deltas keeps them (none are made).
            MorphTarget {
                positions: vec![[0.0; 3]; 6],
                normals: vec![[0.5; 3]; 6],
                ..MorphTarget::default()
            },
        ];
        let mut indices = vec![0, 1, 2, 0, 2, 3];
        let (out, flat) = flat_normals(&v, &mut indices, &targets);
        assert_eq!(out.len(), 6);
        assert_eq!(flat.target_normals.len(), 1);
        let (t, deltas) = &flat.target_normals[0];
        assert_eq!(*t, 0);
        let tilted = Vec3::new(1.0, -1.0, 1.0).normalize();
        for (k, tri) in indices.chunks_exact(3).enumerate() {
            for &i in tri {
                let morphed = Vec3::from(out[i as usize].normal) + Vec3::from(deltas[i as usize]);
                let want = if k == 0 { Vec3::Z } else { tilted };
                assert!(morphed.abs_diff_eq(want, 1e-6), "{morphed} on triangle {k}");
            }
        }
    }

    #[test]
    fn flat_normals_of_a_cone_with_a_huge_apex_stay_linear_and_exact() {
        // 200,000 faces around one apex, each with its own normal: every corner gets its face's
        // normal, and the apex is not compared against every earlier copy (that would be 2e10
        // comparisons: this test would not finish).
        let n = 200_000;
        let mut v = vec![vertex([0.0, 1.0, 0.0], [0.0; 2])];
        v.extend((0..n).map(|k| {
            let a = k as f32 / n as f32 * std::f32::consts::TAU;
            vertex([a.cos(), 0.0, -a.sin()], [0.0; 2])
        }));
        let mut indices: Vec<u32> = (0..n as u32)
            .flat_map(|k| [0, 1 + k, 1 + (k + 1) % n as u32])
            .collect();
        let (out, flat) = flat_normals(&v, &mut indices, &[]);
        assert_eq!(flat.degenerate, 0);
        for tri in indices.chunks_exact(3) {
            let p = [0, 1, 2].map(|c| Vec3::from(out[tri[c] as usize].position));
            let face = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
            for &i in tri {
                let got = Vec3::from(out[i as usize].normal);
                assert!(got.dot(face) > 1.0 - 1e-5, "{got} on a face facing {face}");
            }
        }
    }

    /// Runs MikkTSpace and then the loader's repair, as gltf_load does, and checks that every
    /// vertex ends with a unit tangent orthogonal to its normal and indices still in range.
    fn tangents_of(mut vertices: Vec<Vertex>, mut indices: Vec<u32>) -> (Vec<Vertex>, bool) {
        let ran = mikktspace_tangents(&mut vertices, &mut indices, &|v| v.uv);
        if !ran {
            arbitrary_tangents(&mut vertices);
        }
        repair_tangents(&mut vertices);
        assert!(indices.iter().all(|&i| (i as usize) < vertices.len()));
        for v in &vertices {
            let t = Vec4::from(v.tangent);
            assert!(t.is_finite(), "{t}");
            assert!((t.truncate().length() - 1.0).abs() < 1e-4, "{t}");
            assert!(t.truncate().dot(Vec3::from(v.normal)).abs() < 1e-4, "{t}");
            assert!(t.w == 1.0 || t.w == -1.0, "{t}");
        }
        (vertices, ran)
    }

    /// A unit quad in the XY plane with u along +x and v along +y: tangent +x, and w = -1, the
    /// bitangent w·cross(n, t) = -y pointing towards smaller v, up the image, as a glTF normal
    /// map's +Y does.
    #[test]
    fn a_plain_quad_gets_u_as_its_tangent() {
        let quad = vec![
            vertex([0.0, 0.0, 0.0], [0.0, 0.0]),
            vertex([1.0, 0.0, 0.0], [1.0, 0.0]),
            vertex([1.0, 1.0, 0.0], [1.0, 1.0]),
            vertex([0.0, 1.0, 0.0], [0.0, 1.0]),
        ];
        let (v, ran) = tangents_of(quad, vec![0, 1, 2, 0, 2, 3]);
        assert!(ran);
        assert_eq!(v.len(), 4, "nothing to split");
        for v in v {
            let t = Vec4::from(v.tangent);
            assert!(
                (t - Vec4::new(1.0, 0.0, 0.0, -1.0)).abs().max_element() < 1e-6,
                "{t}"
            );
        }
    }

    /// The inputs mikktspace 0.3 could not take (it read out of bounds on a mesh of triangles
    /// with coincident corners, and panicked welding a mesh whose extent is zero or overflows
    /// f32), which the loader used to keep away from it, now go straight to bevy_mikktspace.
    #[test]
    fn hostile_meshes_get_finite_frames_without_a_workaround() {
        // Only triangles with two corners at one position.
        let coincident = vec![
            vertex([0.0, 0.0, 0.0], [0.0, 0.0]),
            vertex([0.0, 0.0, 0.0], [1.0, 0.0]),
            vertex([1.0, 1.0, 0.0], [1.0, 1.0]),
        ];
        tangents_of(coincident, vec![0, 1, 2, 1, 0, 2, 2, 2, 0]);
        // A collapsed mesh: every corner at one point.
        let point = vec![vertex([2.0, 2.0, 2.0], [0.0, 0.0]); 6];
        tangents_of(point, vec![0, 1, 2, 3, 4, 5]);
        // An extent that overflows f32 (positions at +-3e38).
        let huge = vec![
            vertex([-3e38, -3e38, 0.0], [0.0, 0.0]),
            vertex([3e38, -3e38, 0.0], [1.0, 0.0]),
            vertex([3e38, 3e38, 0.0], [1.0, 1.0]),
            vertex([-3e38, 3e38, 0.0], [0.0, 1.0]),
        ];
        tangents_of(huge, vec![0, 1, 2, 0, 2, 3]);
        // Non-finite positions and zero UV area next to a good triangle.
        let mixed = vec![
            vertex([f32::NAN, 0.0, 0.0], [0.0, 0.0]),
            vertex([f32::INFINITY, 1.0, 0.0], [1.0, 0.0]),
            vertex([0.0, 1.0, 0.0], [1.0, 1.0]),
            vertex([0.0, 0.0, 0.0], [0.0, 0.0]),
            vertex([1.0, 0.0, 0.0], [0.0, 0.0]),
            vertex([1.0, 1.0, 0.0], [0.0, 0.0]),
        ];
        tangents_of(mixed, vec![0, 1, 2, 3, 4, 5, 3, 4, 2]);
        // An index out of range is skipped, not read.
        let mut two = vec![
            vertex([0.0, 0.0, 0.0], [0.0, 0.0]),
            vertex([1.0, 0.0, 0.0], [1.0, 0.0]),
        ];
        assert!(!mikktspace_tangents(&mut two, &mut [0, 1, 7], &|v| v.uv));
        // Nothing at all.
        let (_, ran) = tangents_of(Vec::new(), Vec::new());
        assert!(!ran);
    }

    /// Mirrored UVs on the two halves of a strip: the shared vertices get two tangents with
    /// opposite w, so they are split.
    #[test]
    fn mirrored_uvs_split_the_shared_vertices() {
        let strip = vec![
            vertex([-1.0, 0.0, 0.0], [1.0, 0.0]),
            vertex([0.0, 0.0, 0.0], [0.0, 0.0]),
            vertex([0.0, 1.0, 0.0], [0.0, 1.0]),
            vertex([-1.0, 1.0, 0.0], [1.0, 1.0]),
            vertex([1.0, 0.0, 0.0], [1.0, 0.0]),
            vertex([1.0, 1.0, 0.0], [1.0, 1.0]),
        ];
        let (v, _) = tangents_of(strip, vec![0, 1, 2, 0, 2, 3, 1, 4, 5, 1, 5, 2]);
        assert_eq!(v.len(), 8, "vertices 1 and 2 split once each");
        let ws: Vec<f32> = v.iter().map(|v| v.tangent[3]).collect();
        assert!(ws.contains(&1.0) && ws.contains(&-1.0), "{ws:?}");
    }
}
