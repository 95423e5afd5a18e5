//! glTF animation: the node hierarchy kept from the file, keyframe sampling (step, linear, cubic
//! spline), skins and morph targets, and posing a [`Scene`] at a time of one of its animations.
//!
//! The loader flattens nodes into [`super::Draw`]s with world matrices; the [`Rig`] keeps what a
//! pose needs to redo that: each node's rest transform and parent, which draws, lights and
//! cameras each node places, the skins' joints and inverse bind matrices, and the meshes' joint
//! influences and morph target deltas. [`Scene::pose`] resets every node to its rest transform,
//! applies the animation's channels at the time, and recomputes world matrices, joint matrices,
//! morph weights, lights and cameras; the renderer re-uploads only those
//! (`Renderer::update_pose`). Skinning itself runs on the GPU (glsl/skin.comp); [`deform`] is its
//! CPU twin, used for bounds and by the tests.

use std::collections::BTreeMap;

use glam::{Mat3, Mat4, Quat, Vec3};

use super::{Camera, Scene, Vertex};
use crate::{Error, Result};

/// The most joints a skin may have: JOINTS_n is unsigned byte or unsigned short in glTF, so no
/// vertex can name a joint beyond 65535.
pub const MAX_JOINTS: usize = 1 << 16;
/// The most morph targets a primitive may have. glTF sets no limit; 256 deltas per vertex is far
/// beyond any exporter's (Blender's shape keys; ARKit faces use 52) and bounds the GPU's loop.
pub const MAX_MORPH_TARGETS: usize = 256;

/// An animation as `weft plan` lists it.
#[derive(Clone, Debug, PartialEq)]
pub struct AnimationInfo {
    pub name: String,
    /// The last keyframe time over all channels, in seconds (0 for an animation with no usable
    /// channel).
    pub duration: f32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    Step,
    Linear,
    /// Hermite spline with in- and out-tangents per keyframe (glTF Appendix C).
    CubicSpline,
}

/// What a channel animates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Path {
    Translation,
    Rotation,
    Scale,
    /// Morph target weights (as many per keyframe as the node's mesh has targets).
    Weights,
}

/// One sampler: keyframe times and values. `values` holds `width` floats per keyframe, three
/// times over for cubic splines (in-tangent, value, out-tangent per keyframe, as glTF stores them).
#[derive(Clone, Debug, PartialEq)]
pub struct Sampler {
    pub interpolation: Interpolation,
    /// Strictly increasing, finite, at least one.
    pub times: Vec<f32>,
    pub values: Vec<f32>,
    pub width: usize,
}

impl Sampler {
    /// Checks the keyframes (`what` names the sampler in messages).
    pub fn new(
        interpolation: Interpolation,
        times: Vec<f32>,
        values: Vec<f32>,
        width: usize,
        what: &str,
    ) -> std::result::Result<Sampler, String> {
        Sampler::counted(interpolation, times, values, width, width, what)
    }

    /// [`Sampler::new`], with messages counting the output accessor's elements of `element`
    /// floats each (`width` for a vector, 1 for morph weights, which glTF stores as scalars,
    /// `width` of them per keyframe).
    fn counted(
        interpolation: Interpolation,
        times: Vec<f32>,
        values: Vec<f32>,
        width: usize,
        element: usize,
        what: &str,
    ) -> std::result::Result<Sampler, String> {
        if times.is_empty() {
            return Err(format!("{what} has no keyframes"));
        }
        if let Some(k) = times.iter().position(|t| !t.is_finite() || *t < 0.0) {
            return Err(format!(
                "{what} has the keyframe time {} at keyframe {k}; times must be finite and not negative",
                times[k]
            ));
        }
        if let Some(k) = times.windows(2).position(|w| w[1] <= w[0]) {
            return Err(format!(
                "{what} has keyframe times that do not increase ({} then {} at keyframes {k} and {}); glTF requires strictly increasing times",
                times[k],
                times[k + 1],
                k + 1
            ));
        }
        let per_key = if interpolation == Interpolation::CubicSpline {
            3 * width
        } else {
            width
        };
        if width == 0 || values.len() != times.len() * per_key {
            let element = element.max(1);
            return Err(format!(
                "{what} has {} keyframe times but {} output values; {:?} interpolation needs {} value(s) per keyframe ({} in all)",
                times.len(),
                values.len() / element,
                interpolation,
                per_key / element,
                times.len() * per_key / element
            ));
        }
        if values.iter().any(|v| !v.is_finite()) {
            return Err(format!("{what} has a non-finite output value"));
        }
        Ok(Sampler {
            interpolation,
            times,
            values,
            width,
        })
    }

    /// The value at keyframe `k` (the middle third of a cubic spline's triple).
    fn value(&self, k: usize) -> &[f32] {
        let w = self.width;
        match self.interpolation {
            Interpolation::CubicSpline => &self.values[(3 * k + 1) * w..(3 * k + 2) * w],
            _ => &self.values[k * w..(k + 1) * w],
        }
    }

    /// Samples at `t` into `out` (`width` floats). Before the first keyframe the first value
    /// holds, after the last the last (glTF: the animation clamps). `rotation` makes the samples
    /// unit quaternions: linear interpolation is slerp along the shorter arc, cubic splines are
    /// normalised.
    pub fn sample(&self, t: f32, rotation: bool, out: &mut [f32]) {
        let w = self.width;
        let n = self.times.len();
        let last = n - 1;
        if n == 1 || t <= self.times[0] || t.is_nan() {
            out.copy_from_slice(self.value(0));
            return;
        }
        if t >= self.times[last] {
            out.copy_from_slice(self.value(last));
            return;
        }
        // The keyframe interval [times[k], times[k + 1]) holding t.
        let k = self.times.partition_point(|&x| x <= t) - 1;
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let dt = t1 - t0;
        let s = (t - t0) / dt;
        match self.interpolation {
            Interpolation::Step => out.copy_from_slice(self.value(k)),
            Interpolation::Linear => {
                let (a, b) = (self.value(k), self.value(k + 1));
                if rotation && w == 4 {
                    let q = slerp(quat(a), quat(b), s);
                    out.copy_from_slice(&q.to_array());
                } else {
                    for i in 0..w {
                        out[i] = a[i] + (b[i] - a[i]) * s;
                    }
                }
            }
            Interpolation::CubicSpline => {
                let v = &self.values;
                let (s2, s3) = (s * s, s * s * s);
                let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
                let h10 = s3 - 2.0 * s2 + s;
                let h01 = -2.0 * s3 + 3.0 * s2;
                let h11 = s3 - s2;
                for i in 0..w {
                    let p0 = v[(3 * k + 1) * w + i];
                    // The out-tangent of k and the in-tangent of k + 1, scaled by the interval.
                    let m0 = v[(3 * k + 2) * w + i] * dt;
                    let m1 = v[(3 * (k + 1)) * w + i] * dt;
                    let p1 = v[(3 * (k + 1) + 1) * w + i];
                    out[i] = h00 * p0 + h10 * m0 + h01 * p1 + h11 * m1;
                }
                if rotation && w == 4 {
                    let q = quat(out).normalize();
                    let q = if q.is_finite() {
                        q
                    } else {
                        quat(self.value(k)).normalize()
                    };
                    out.copy_from_slice(&q.to_array());
                }
            }
        }
    }

    /// The last keyframe time.
    pub fn end(&self) -> f32 {
        self.times.last().copied().unwrap_or(0.0)
    }
}

fn quat(v: &[f32]) -> Quat {
    Quat::from_xyzw(v[0], v[1], v[2], v[3])
}

/// Spherical linear interpolation from `a` to `b` along the shorter arc (b is negated when the
/// two are more than 90 degrees apart in quaternion space), normalised.
pub fn slerp(a: Quat, b: Quat, s: f32) -> Quat {
    let (a, mut b) = (a.normalize(), b.normalize());
    let mut d = a.dot(b);
    if d < 0.0 {
        b = -b;
        d = -d;
    }
    if d > 0.9995 {
        // Nearly parallel: linear, then normalised (sin θ is too small to divide by).
        return (a + (b - a) * s).normalize();
    }
    let theta = d.clamp(-1.0, 1.0).acos();
    let sin = theta.sin();
    let wa = ((1.0 - s) * theta).sin() / sin;
    let wb = (s * theta).sin() / sin;
    (a * wa + b * wb).normalize()
}

/// A channel: a sampler driving one property of one node.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// Index into [`Rig::nodes`].
    pub node: usize,
    pub path: Path,
    pub sampler: Sampler,
}

impl Channel {
    /// A channel on `path` of `node` from a sampler's keyframes, checked as [`Sampler::new`]
    /// checks them and for what `path` needs: a rotation's keyframe values must be quaternions
    /// of non-zero length (glTF stores unit ones; a zero one is no rotation at all and would
    /// collapse the node or, interpolated, make its transform NaN). They are normalised, so
    /// STEP and LINEAR sampling see unit quaternions. The error says why the channel cannot be
    /// used (the loader drops it with a warning).
    pub fn new(
        node: usize,
        path: Path,
        interpolation: Interpolation,
        times: Vec<f32>,
        values: Vec<f32>,
        width: usize,
    ) -> std::result::Result<Channel, String> {
        let element = if path == Path::Weights { 1 } else { width };
        let mut sampler =
            Sampler::counted(interpolation, times, values, width, element, "its sampler")?;
        if path == Path::Rotation && width == 4 {
            for k in 0..sampler.times.len() {
                let q = quat(sampler.value(k));
                let length = q.length();
                if !(length > 1e-6 && length.is_finite()) {
                    return Err(format!(
                        "rotates by the quaternion {:?} at keyframe {k}, which has {} length; a rotation keyframe must be a unit quaternion",
                        q.to_array(),
                        if length.is_finite() { "zero" } else { "no finite" }
                    ));
                }
                if interpolation != Interpolation::CubicSpline {
                    let unit = q / length;
                    sampler.values[k * 4..k * 4 + 4].copy_from_slice(&unit.to_array());
                }
            }
        }
        Ok(Channel {
            node,
            path,
            sampler,
        })
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Animation {
    pub name: String,
    pub channels: Vec<Channel>,
}

/// A node of the file, as a pose needs it.
#[derive(Clone, Debug)]
pub struct Node {
    pub parent: Option<usize>,
    /// A node given by `matrix` is not animatable (glTF forbids channels on it).
    pub matrix: Option<Mat4>,
    pub translation: Vec3,
    pub rotation: Quat,
    pub scale: Vec3,
    /// The node's morph weights at rest (the node's `weights`, else its mesh's).
    pub weights: Vec<f32>,
}

impl Node {
    fn local(&self, t: Vec3, r: Quat, s: Vec3) -> Mat4 {
        self.matrix
            .unwrap_or_else(|| Mat4::from_scale_rotation_translation(s, r, t))
    }
}

/// A skin: its joints (nodes) and their inverse bind matrices.
#[derive(Clone, Debug)]
pub struct Skin {
    pub name: String,
    pub joints: Vec<usize>,
    pub inverse_bind: Vec<Mat4>,
    /// World from bind-pose object space, per joint (world of the joint × inverse bind): a skinned
    /// vertex lands in world space, so a skinned draw's own world matrix is the identity (glTF
    /// ignores the transform of a skinned mesh's node).
    pub joint_matrices: Vec<Mat4>,
}

/// Per vertex: up to four joints (indices into the skin's joint list) and their weights.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VertexSkin {
    pub joints: [u32; 4],
    pub weights: [f32; 4],
}

/// One morph target's per-vertex deltas (empty where the target does not move that attribute).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MorphTarget {
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub tangents: Vec<[f32; 3]>,
}

/// How a mesh deforms: joint influences (empty: not skinned) and morph targets.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshDeform {
    pub skin: Vec<VertexSkin>,
    pub targets: Vec<MorphTarget>,
}

impl MeshDeform {
    /// Appends copies of vertices `origin` (the vertices split off by tangent generation, in
    /// order): they move as their originals.
    pub fn extend_to(&mut self, origin: &[usize]) {
        for &o in origin {
            if !self.skin.is_empty() {
                let s = self.skin.get(o).copied().unwrap_or_default();
                self.skin.push(s);
            }
            for t in &mut self.targets {
                for list in [&mut t.positions, &mut t.normals, &mut t.tangents] {
                    if !list.is_empty() {
                        let d = list.get(o).copied().unwrap_or([0.0; 3]);
                        list.push(d);
                    }
                }
            }
        }
    }
}

/// A draw a node places: which node, the skin that deforms it, its current morph weights.
#[derive(Clone, Debug, PartialEq)]
pub struct DrawBinding {
    /// Index into `Scene::draws`.
    pub draw: usize,
    pub node: usize,
    pub skin: Option<usize>,
    /// The current morph weights (one per target of the draw's mesh).
    pub weights: Vec<f32>,
    /// The instance's transform under its node (EXT_mesh_gpu_instancing; identity otherwise):
    /// the draw's world is the node's world times this.
    pub instance: Mat4,
}

/// What posing needs beyond the flattened scene.
#[derive(Clone, Debug, Default)]
pub struct Rig {
    pub nodes: Vec<Node>,
    /// Node indices with every parent before its children (the nodes the scene reaches).
    pub order: Vec<usize>,
    pub skins: Vec<Skin>,
    pub animations: Vec<Animation>,
    pub infos: Vec<AnimationInfo>,
    pub draws: Vec<DrawBinding>,
    /// By mesh index (`Scene::meshes`): the meshes that deform.
    pub meshes: BTreeMap<usize, MeshDeform>,
    /// (index into `Scene::lights`, node) and (index into `Scene::cameras`, node).
    pub lights: Vec<(usize, usize)>,
    pub cameras: Vec<(usize, usize)>,
}

impl Rig {
    /// World matrices of every node with each node's (translation, rotation, scale) given.
    fn world_matrices(&self, trs: &[(Vec3, Quat, Vec3)]) -> Vec<Mat4> {
        let mut world = vec![Mat4::IDENTITY; self.nodes.len()];
        for &i in &self.order {
            let n = &self.nodes[i];
            let (t, r, s) = trs[i];
            let local = n.local(t, r, s);
            world[i] = match n.parent {
                Some(p) => world[p] * local,
                None => local,
            };
        }
        world
    }

    /// The binding of draw `draw`, if a node places it.
    pub fn binding(&self, draw: usize) -> Option<&DrawBinding> {
        self.draws.iter().find(|b| b.draw == draw)
    }

    /// Whether draw `draw` is deformed (skinned or morphed) on the GPU.
    pub fn deforms(&self, scene_mesh: usize, binding: &DrawBinding) -> bool {
        binding.skin.is_some()
            || self
                .meshes
                .get(&scene_mesh)
                .is_some_and(|m| !m.targets.is_empty())
    }
}

/// A camera's view from the world matrix of the node that holds it: the inverse of the node's
/// rigid motion (scale, even mirroring, removed; -Z the view direction, +Y up). None when the
/// node scales it to nothing.
pub(super) fn camera_view(world: Mat4) -> Option<Mat4> {
    let z = world.z_axis.truncate().try_normalize()?;
    let y = world.y_axis.truncate();
    let y = (y - z * z.dot(y)).try_normalize()?;
    let x = y.cross(z);
    let rigid = Mat4::from_cols(x.extend(0.0), y.extend(0.0), z.extend(0.0), world.w_axis);
    Some(rigid.inverse())
}

/// The position and direction (-Z, unit) of a light placed by a node with this world matrix.
pub(super) fn light_frame(world: Mat4) -> Option<(Vec3, Vec3)> {
    let d = (world * glam::Vec4::new(0.0, 0.0, -1.0, 0.0))
        .truncate()
        .try_normalize()?;
    Some((world.w_axis.truncate(), d))
}

impl Scene {
    /// The file's animations, with their durations.
    pub fn animations(&self) -> &[AnimationInfo] {
        &self.rig.infos
    }

    /// The index of an animation given by name or by index (`--animation NAME|INDEX`).
    pub fn find_animation(&self, name_or_index: &str) -> Result<usize> {
        let list = || {
            if self.rig.infos.is_empty() {
                "it has no animations".to_string()
            } else {
                format!(
                    "its animations are: {}",
                    self.rig
                        .infos
                        .iter()
                        .enumerate()
                        .map(|(i, a)| format!("{i} '{}'", a.name))
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            }
        };
        if let Some(i) = self.rig.infos.iter().position(|a| a.name == name_or_index) {
            return Ok(i);
        }
        match name_or_index.parse::<usize>() {
            Ok(i) if i < self.rig.infos.len() => Ok(i),
            _ => Err(Error::input(format!(
                "{} has no animation '{name_or_index}'; {} (`weft plan` lists them): pass a name or an index",
                self.source,
                list()
            ))),
        }
    }

    /// Pose the scene at `time` seconds of animation `index` (times outside [0, duration] clamp
    /// per glTF sampling rules): updates draws' world matrices, cameras, lights, joint matrices,
    /// morph weights. Every node not animated by `index` is at its rest transform, whatever the
    /// previous pose was.
    pub fn pose(&mut self, index: usize, time: f32) -> Result<()> {
        let Some(animation) = self.rig.animations.get(index) else {
            return Err(Error::input(format!(
                "animation {index} does not exist in {}: it has {} animation(s) (`weft plan` lists them)",
                self.source,
                self.rig.animations.len()
            )));
        };
        if !time.is_finite() {
            return Err(Error::input(format!(
                "animation time {time} is not a finite number of seconds; pass e.g. --time 0.5"
            )));
        }
        let rig = &self.rig;
        let mut trs: Vec<(Vec3, Quat, Vec3)> = rig
            .nodes
            .iter()
            .map(|n| (n.translation, n.rotation, n.scale))
            .collect();
        let mut weights: Vec<Vec<f32>> = rig.nodes.iter().map(|n| n.weights.clone()).collect();
        let mut buf = Vec::new();
        for c in &animation.channels {
            buf.resize(c.sampler.width, 0.0);
            c.sampler.sample(time, c.path == Path::Rotation, &mut buf);
            let (t, r, s) = &mut trs[c.node];
            match c.path {
                Path::Translation => *t = Vec3::from_slice(&buf),
                Path::Rotation => *r = quat(&buf),
                Path::Scale => *s = Vec3::from_slice(&buf),
                Path::Weights => {
                    let w = &mut weights[c.node];
                    let n = w.len().min(buf.len());
                    w[..n].copy_from_slice(&buf[..n]);
                }
            }
        }
        self.apply_pose(&trs, &weights)
    }

    /// Puts every node back at rest (the pose of the file without animation).
    pub fn rest_pose(&mut self) -> Result<()> {
        let trs: Vec<_> = self
            .rig
            .nodes
            .iter()
            .map(|n| (n.translation, n.rotation, n.scale))
            .collect();
        let weights: Vec<_> = self.rig.nodes.iter().map(|n| n.weights.clone()).collect();
        self.apply_pose(&trs, &weights)
    }

    fn apply_pose(&mut self, trs: &[(Vec3, Quat, Vec3)], weights: &[Vec<f32>]) -> Result<()> {
        let world = self.rig.world_matrices(trs);
        if let Some(i) = world.iter().position(|m| !m.is_finite()) {
            return Err(Error::input(format!(
                "{}: node {i} has a world transform that is not finite in this pose (its or its parents' translation, rotation or scale, as the file or the animation sets them, overflow 32-bit floating point); check the node and the animation's output values",
                self.source
            )));
        }
        // Finite factors can still overflow: each product the GPU will use is checked where it
        // is made, so a mesh never vanishes silently.
        for skin in &mut self.rig.skins {
            for (k, &j) in skin.joints.iter().enumerate() {
                let m = world[j] * skin.inverse_bind[k];
                if !m.is_finite() {
                    return Err(Error::input(format!(
                        "{}: skin '{}': the matrix of joint {k} (node {j}'s world transform times its inverse bind matrix) overflows 32-bit floating point in this pose; check the skin's inverse bind matrices and the joint's scale",
                        self.source, skin.name
                    )));
                }
                skin.joint_matrices[k] = m;
            }
        }
        let mut bindings = std::mem::take(&mut self.rig.draws);
        for b in &mut bindings {
            if let Some(d) = self.draws.get_mut(b.draw) {
                d.world = if b.skin.is_some() {
                    Mat4::IDENTITY
                } else {
                    world[b.node] * b.instance
                };
            }
            let w = &weights[b.node];
            for (k, x) in b.weights.iter_mut().enumerate() {
                *x = w.get(k).copied().unwrap_or(0.0);
            }
        }
        self.rig.draws = bindings;
        self.check_deformed()?;
        for &(l, n) in &self.rig.lights {
            if let (Some(light), Some((p, d))) = (self.lights.get_mut(l), light_frame(world[n])) {
                light.position = p;
                light.direction = d;
            }
        }
        for &(c, n) in &self.rig.cameras {
            if let (Some(camera), Some(view)) = (self.cameras.get_mut(c), camera_view(world[n])) {
                camera.view = view;
            }
        }
        Ok(())
    }

    /// Refuses a pose in which a deforming draw's morph targets (weights times deltas) or skin
    /// (joint matrices times positions) take a vertex out of 32-bit floating point: the GPU
    /// would draw NaN, and the mesh would vanish without a word.
    fn check_deformed(&self) -> Result<()> {
        let empty = MeshDeform::default();
        for b in &self.rig.draws {
            let Some(d) = self.draws.get(b.draw) else {
                continue;
            };
            let Some(mesh) = self.meshes.get(d.mesh) else {
                continue;
            };
            if !self.rig.deforms(d.mesh, b) {
                continue;
            }
            let deform = self.rig.meshes.get(&d.mesh).unwrap_or(&empty);
            let skin = b.skin.and_then(|s| self.rig.skins.get(s));
            let joints = skin.map(|s| &s.joint_matrices[..]);
            let morphed = b.weights.iter().any(|w| *w != 0.0);
            if !morphed && joints.is_none() {
                continue;
            }
            for (i, v) in mesh.vertices.iter().enumerate() {
                let (p, n, t) = deform_raw(v, i, deform, &b.weights, None);
                let by = if !(p.is_finite() && n.is_finite() && t.is_finite()) && morphed {
                    format!(
                        "its morph targets (weights {:?} times the targets' deltas)",
                        b.weights
                    )
                } else if joints.is_some() && {
                    let (p, n, t) = deform_raw(v, i, deform, &b.weights, joints);
                    !(p.is_finite() && n.is_finite() && t.is_finite())
                } {
                    format!(
                        "its skin '{}' (the joint matrices times the vertex)",
                        skin.map_or("", |s| s.name.as_str())
                    )
                } else {
                    continue;
                };
                return Err(Error::input(format!(
                    "{}: mesh '{}' (node {}): {by} move vertex {i} out of the range of 32-bit floating point in this pose, so the mesh cannot be drawn; check the morph weights and target deltas, or the skin's inverse bind matrices and joint scales",
                    self.source, mesh.name, b.node
                )));
            }
        }
        Ok(())
    }

    /// The vertices of draw `draw` as the GPU deforms them (morph targets, then skinning; the
    /// CPU twin of glsl/skin.comp), in the space the draw's world matrix maps from (world space for
    /// skinned draws, whose world is the identity). None for a draw that does not deform.
    pub fn deformed_vertices(&self, draw: usize) -> Option<Vec<Vertex>> {
        let b = self.rig.binding(draw)?;
        let d = self.draws.get(draw)?;
        let mesh = self.meshes.get(d.mesh)?;
        if !self.rig.deforms(d.mesh, b) {
            return None;
        }
        let empty = MeshDeform::default();
        let deform = self.rig.meshes.get(&d.mesh).unwrap_or(&empty);
        let joints = b
            .skin
            .and_then(|s| self.rig.skins.get(s))
            .map(|s| &s.joint_matrices[..]);
        Some(
            mesh.vertices
                .iter()
                .enumerate()
                .map(|(i, v)| deform_vertex(v, i, deform, &b.weights, joints))
                .collect(),
        )
    }
}

/// One vertex through the morph targets (weighted deltas) and the skin (the weighted sum of its
/// joints' matrices): position transformed, normal by the cofactor matrix (the inverse transpose
/// up to scale), tangent by the matrix and made orthogonal to the normal again, its handedness
/// flipped where the skin mirrors. Mirrored exactly by glsl/skin.comp.
pub fn deform_vertex(
    v: &Vertex,
    index: usize,
    deform: &MeshDeform,
    weights: &[f32],
    joints: Option<&[Mat4]>,
) -> Vertex {
    let (p, n, t) = deform_raw(v, index, deform, weights, joints);
    let w = v.tangent[3] * skin_sign(index, deform, joints);
    let n = n.try_normalize().unwrap_or(Vec3::Z);
    let t = (t - n * n.dot(t))
        .try_normalize()
        .unwrap_or_else(|| n.any_orthonormal_vector());
    Vertex {
        position: p.to_array(),
        normal: n.to_array(),
        tangent: [t.x, t.y, t.z, w],
        ..*v
    }
}

/// The skin matrix of vertex `index` (the weighted sum of its joints' matrices), None when not
/// skinned.
fn skin_matrix(index: usize, deform: &MeshDeform, joints: Option<&[Mat4]>) -> Option<Mat4> {
    let (joints, s) = (joints?, deform.skin.get(index)?);
    let mut m = Mat4::ZERO;
    for k in 0..4 {
        if let Some(j) = joints.get(s.joints[k] as usize) {
            m += *j * s.weights[k];
        }
    }
    Some(m)
}

/// -1 where the skin mirrors vertex `index`, else 1.
fn skin_sign(index: usize, deform: &MeshDeform, joints: Option<&[Mat4]>) -> f32 {
    match skin_matrix(index, deform, joints) {
        Some(m) if Mat3::from_mat4(m).determinant() < 0.0 => -1.0,
        _ => 1.0,
    }
}

/// [`deform_vertex`] before normalising: position, normal and tangent (xyz) as morphed and
/// skinned, where overflow shows as non-finite values.
fn deform_raw(
    v: &Vertex,
    index: usize,
    deform: &MeshDeform,
    weights: &[f32],
    joints: Option<&[Mat4]>,
) -> (Vec3, Vec3, Vec3) {
    let mut p = Vec3::from(v.position);
    let mut n = Vec3::from(v.normal);
    let mut t = Vec3::new(v.tangent[0], v.tangent[1], v.tangent[2]);
    for (target, &k) in deform.targets.iter().zip(weights) {
        if let Some(d) = target.positions.get(index) {
            p += Vec3::from(*d) * k;
        }
        if let Some(d) = target.normals.get(index) {
            n += Vec3::from(*d) * k;
        }
        if let Some(d) = target.tangents.get(index) {
            t += Vec3::from(*d) * k;
        }
    }
    if let Some(m) = skin_matrix(index, deform, joints) {
        p = m.transform_point3(p);
        let m3 = Mat3::from_mat4(m);
        let det = m3.determinant();
        let cof = cofactor(m3);
        let sign = if det < 0.0 { -1.0 } else { 1.0 };
        n = cof * n * sign;
        t = m3 * t;
    }
    (p, n, t)
}

/// The cofactor matrix of `m` (det(m) · m⁻ᵀ, defined for singular m too): what normals transform
/// by, before normalising.
pub fn cofactor(m: Mat3) -> Mat3 {
    let (a, b, c) = (m.x_axis, m.y_axis, m.z_axis);
    Mat3::from_cols(b.cross(c), c.cross(a), a.cross(b))
}

/// A camera placed by node `node` in pose `world` (used by the loader too).
pub(super) fn placed_camera(
    name: String,
    world: Mat4,
    yfov: f32,
    znear: f32,
    zfar: Option<f32>,
    aspect_ratio: Option<f32>,
) -> Option<Camera> {
    Some(Camera {
        name,
        view: camera_view(world)?,
        yfov,
        znear,
        zfar,
        aspect_ratio,
        orthographic: None,
        framing: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sampler(i: Interpolation, times: &[f32], values: &[f32], width: usize) -> Sampler {
        Sampler::new(i, times.to_vec(), values.to_vec(), width, "test").unwrap()
    }

    fn at(s: &Sampler, t: f32, rotation: bool) -> Vec<f32> {
        let mut out = vec![0.0; s.width];
        s.sample(t, rotation, &mut out);
        out
    }

    #[test]
    fn step_holds_the_previous_keyframe() {
        let s = sampler(
            Interpolation::Step,
            &[1.0, 2.0, 4.0],
            &[10.0, 20.0, 40.0],
            1,
        );
        assert_eq!(at(&s, 0.0, false), [10.0]); // before the first: clamped
        assert_eq!(at(&s, 1.0, false), [10.0]);
        assert_eq!(at(&s, 1.99, false), [10.0]);
        assert_eq!(at(&s, 2.0, false), [20.0]);
        assert_eq!(at(&s, 3.9, false), [20.0]);
        assert_eq!(at(&s, 9.0, false), [40.0]); // after the last: clamped
    }

    #[test]
    fn linear_interpolates_and_clamps() {
        let s = sampler(
            Interpolation::Linear,
            &[0.0, 2.0],
            &[0.0, 1.0, 2.0, 4.0, 5.0, 6.0],
            3,
        );
        // At t = 0.5: a quarter of the way, by hand: 0 + 4/4, 1 + 4/4, 2 + 4/4.
        assert_eq!(at(&s, 0.5, false), [1.0, 2.0, 3.0]);
        assert_eq!(at(&s, -1.0, false), [0.0, 1.0, 2.0]);
        assert_eq!(at(&s, 5.0, false), [4.0, 5.0, 6.0]);
    }

    #[test]
    fn cubic_spline_scales_tangents_by_the_keyframe_interval() {
        // One scalar, keyframes at t = 1 and t = 3 (interval 2): values 0 and 1, out-tangent of
        // the first 1.5, in-tangent of the second -0.5 (the others unused).
        // Layout per keyframe: in, value, out.
        let s = sampler(
            Interpolation::CubicSpline,
            &[1.0, 3.0],
            &[9.0, 0.0, 1.5, -0.5, 1.0, 9.0],
            1,
        );
        // At t = 2: s = 0.5, h00 = 0.5, h10 = 0.125, h01 = 0.5, h11 = -0.125;
        // p = 0.5·0 + 0.125·(1.5·2) + 0.5·1 - 0.125·(-0.5·2) = 0.375 + 0.5 + 0.125 = 1.0.
        let v = at(&s, 2.0, false)[0];
        assert!((v - 1.0).abs() < 1e-6, "{v}");
        // At t = 1.5: s = 0.25: h00 = 0.84375, h10 = 0.140625, h01 = 0.15625, h11 = -0.046875;
        // p = 0.140625·3 + 0.15625 + 0.046875·1 = 0.421875 + 0.15625 + 0.046875 = 0.625.
        let v = at(&s, 1.5, false)[0];
        assert!((v - 0.625).abs() < 1e-6, "{v}");
        // Without the interval scaling it would be 0.140625·1.5 + 0.15625 + 0.0234375 = 0.390625:
        // the case above tells the two apart. Clamped outside: the values, not the tangents.
        assert_eq!(at(&s, 0.0, false), [0.0]);
        assert_eq!(at(&s, 7.0, false), [1.0]);
    }

    #[test]
    fn slerp_takes_the_shorter_arc() {
        // 0 and 270 degrees about z; 270 degrees is -90 the short way, and the quaternion for it
        // is given with w < 0 (the long representation): halfway must be -45 degrees.
        let a = Quat::IDENTITY;
        let b = Quat::from_rotation_z(270f32.to_radians());
        assert!(a.dot(b) < 0.0);
        let s = sampler(
            Interpolation::Linear,
            &[0.0, 1.0],
            &[a.x, a.y, a.z, a.w, b.x, b.y, b.z, b.w],
            4,
        );
        let q = quat(&at(&s, 0.5, true));
        let expect = Quat::from_rotation_z(-45f32.to_radians());
        assert!(q.dot(expect).abs() > 1.0 - 1e-6, "{q:?} vs {expect:?}");
        // And a quarter of the way along 0..90 degrees is 22.5 degrees (constant angular speed,
        // which a normalised lerp does not have: it would give 20.7).
        let b = Quat::from_rotation_z(90f32.to_radians());
        let q = slerp(a, b, 0.25);
        let angle = 2.0 * q.z.atan2(q.w);
        assert!(
            (angle.to_degrees() - 22.5).abs() < 1e-4,
            "{}",
            angle.to_degrees()
        );
    }

    #[test]
    fn cubic_rotation_is_normalised() {
        let a = Quat::IDENTITY;
        let b = Quat::from_rotation_x(1.0);
        let z = [0.0f32; 4];
        let mut v = Vec::new();
        v.extend_from_slice(&z);
        v.extend_from_slice(&a.to_array());
        v.extend_from_slice(&z);
        v.extend_from_slice(&z);
        v.extend_from_slice(&b.to_array());
        v.extend_from_slice(&z);
        let s = sampler(Interpolation::CubicSpline, &[0.0, 1.0], &v, 4);
        let q = quat(&at(&s, 0.3, true));
        assert!((q.length() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn bad_keyframes_are_refused_with_a_reason() {
        let e = Sampler::new(
            Interpolation::Linear,
            vec![0.0, 1.0, 1.0],
            vec![0.0; 3],
            1,
            "s",
        )
        .unwrap_err();
        assert!(e.contains("do not increase"), "{e}");
        let e =
            Sampler::new(Interpolation::Linear, vec![0.0, 1.0], vec![0.0; 3], 1, "s").unwrap_err();
        assert!(e.contains("2 keyframe times but 3 output values"), "{e}");
        let e = Sampler::new(
            Interpolation::CubicSpline,
            vec![0.0, 1.0],
            vec![0.0; 2],
            1,
            "s",
        )
        .unwrap_err();
        assert!(e.contains("3 value(s) per keyframe"), "{e}");
        let e = Sampler::new(Interpolation::Step, vec![f32::NAN], vec![0.0], 1, "s").unwrap_err();
        assert!(e.contains("finite"), "{e}");
        assert!(Sampler::new(Interpolation::Step, vec![], vec![], 1, "s").is_err());
    }

    #[test]
    fn skinned_tangent_follows_the_joint_and_keeps_handedness() {
        // A vertex fully bound to a joint turned 90 degrees about z and mirrored in x.
        let v = Vertex {
            position: [1.0, 0.0, 0.0],
            normal: [0.0, 0.0, 1.0],
            tangent: [1.0, 0.0, 0.0, 1.0],
            ..Default::default()
        };
        let deform = MeshDeform {
            skin: vec![VertexSkin {
                joints: [0, 0, 0, 0],
                weights: [1.0, 0.0, 0.0, 0.0],
            }],
            targets: Vec::new(),
        };
        let turn = Mat4::from_rotation_z(90f32.to_radians());
        let out = deform_vertex(&v, 0, &deform, &[], Some(&[turn]));
        let close = |a: [f32; 3], b: [f32; 3]| (0..3).all(|k| (a[k] - b[k]).abs() < 1e-6);
        assert!(close(out.position, [0.0, 1.0, 0.0]));
        assert!(close(
            [out.tangent[0], out.tangent[1], out.tangent[2]],
            [0.0, 1.0, 0.0]
        ));
        assert_eq!(out.tangent[3], 1.0);
        let mirror = Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
        let out = deform_vertex(&v, 0, &deform, &[], Some(&[mirror]));
        assert!(close(out.normal, [0.0, 0.0, 1.0]));
        assert!(close(
            [out.tangent[0], out.tangent[1], out.tangent[2]],
            [-1.0, 0.0, 0.0]
        ));
        assert_eq!(out.tangent[3], -1.0);
    }
}
