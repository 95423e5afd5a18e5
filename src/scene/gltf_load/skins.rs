//! Animation: the rig of nodes, skins and their joints, and animation channels.

use super::*;

impl<'a> Loader<'a> {
    /// Every node's parent, rest transform and rest morph weights ([`animation::Rig::nodes`], by
    /// glTF node index).
    pub(super) fn rig_nodes(&mut self) -> Result<()> {
        let doc = self.doc;
        let mut parent = vec![None; doc.nodes().len()];
        for node in doc.nodes() {
            for child in node.children() {
                if let Some(p) = parent.get_mut(child.index()) {
                    *p = Some(node.index());
                }
            }
        }
        for node in doc.nodes() {
            let targets = node
                .mesh()
                .and_then(|m| m.primitives().next())
                .map_or(0, |p| p.morph_targets().len());
            let weights = node
                .weights()
                .or_else(|| node.mesh().and_then(|m| m.weights()))
                .map(<[f32]>::to_vec)
                .unwrap_or_else(|| vec![0.0; targets]);
            if weights.iter().any(|w| !w.is_finite()) {
                return Err(self.error(format_args!(
                    "node {} (or its mesh) has a non-finite morph target weight in {weights:?}; set finite weights",
                    node.index()
                )));
            }
            let (matrix, translation, rotation, scale) = match node.transform() {
                gltf::scene::Transform::Matrix { matrix } => (
                    Some(Mat4::from_cols_array_2d(&matrix)),
                    Vec3::ZERO,
                    Quat::IDENTITY,
                    Vec3::ONE,
                ),
                gltf::scene::Transform::Decomposed {
                    translation,
                    rotation,
                    scale,
                } => {
                    let q = Quat::from_array(rotation);
                    // The walk refuses a bad quaternion on nodes the scene reaches.
                    let q = if q.length_squared() > 1e-12 && q.is_finite() {
                        q.normalize()
                    } else {
                        Quat::IDENTITY
                    };
                    (None, Vec3::from(translation), q, Vec3::from(scale))
                }
            };
            // KHR_node_visibility: `visible` false hides the node and its subtree.
            if let Some(ext) = node.extension_value(NODE_VISIBILITY) {
                let visible = match ext.get("visible") {
                    None => true,
                    Some(serde_json::Value::Bool(b)) => *b,
                    Some(other) => {
                        self.warn(format_args!(
                            "node {} has {NODE_VISIBILITY} \"visible\": {other}, which is not true or false; the node is shown",
                            node.index()
                        ));
                        true
                    }
                };
                if !visible {
                    let n = doc.nodes().len();
                    let list = &mut self.scene.rig.visible;
                    list.resize(n, true);
                    list[node.index()] = false;
                }
            }
            self.scene.rig.nodes.push(animation::Node {
                parent: parent.get(node.index()).copied().flatten(),
                matrix,
                translation,
                rotation,
                scale,
                weights,
            });
        }
        Ok(())
    }

    /// The file's skins (by glTF skin index), checked against the draws that use them.
    pub(super) fn load_skins(&mut self) -> Result<()> {
        let doc = self.doc;
        for skin in doc.skins() {
            let name = skin
                .name()
                .map(str::to_owned)
                .unwrap_or_else(|| format!("skin {}", skin.index()));
            let who = format!("skin '{name}'");
            let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
            if joints.len() > animation::MAX_JOINTS {
                return Err(self.error(format_args!(
                    "{who} has {} joints, more than glTF's limit of {} (joint indices are unsigned shorts); split the skeleton",
                    joints.len(),
                    animation::MAX_JOINTS
                )));
            }
            let inverse_bind = match skin.inverse_bind_matrices() {
                None => vec![Mat4::IDENTITY; joints.len()],
                Some(acc) => {
                    let what = format!("{who}, inverseBindMatrices");
                    let index = acc.index();
                    let values = accessor::read_f32(
                        &acc,
                        Dimensions::Mat4,
                        self.buffers,
                        &Use {
                            source: &self.label,
                            what: &what,
                        },
                    )?;
                    let m: Vec<Mat4> = values.chunks_exact(16).map(Mat4::from_cols_slice).collect();
                    if m.len() != joints.len() {
                        return Err(self.error(format_args!(
                            "{who} has {} joints but its inverseBindMatrices (accessor {index}) hold {} matrices; glTF requires one per joint: re-export the skin",
                            joints.len(),
                            m.len()
                        )));
                    }
                    if let Some(k) = m.iter().position(|m| !m.is_finite()) {
                        return Err(self.error(format_args!(
                            "{who}: inverse bind matrix {k} is not finite; re-export the skin"
                        )));
                    }
                    m
                }
            };
            self.scene.rig.skins.push(animation::Skin {
                name,
                joint_matrices: vec![Mat4::IDENTITY; joints.len()],
                joints,
                inverse_bind,
            });
        }
        for b in &self.scene.rig.draws {
            let Some(s) = b.skin else { continue };
            let Some(d) = self.scene.draws.get(b.draw) else {
                continue;
            };
            let skin = &self.scene.rig.skins[s];
            let mesh = &self.scene.meshes[d.mesh];
            let Some(deform) = self.scene.rig.meshes.get(&d.mesh) else {
                continue;
            };
            for (v, vs) in deform.skin.iter().enumerate() {
                if let Some(k) = (0..4)
                    .find(|&k| vs.weights[k] > 0.0 && vs.joints[k] as usize >= skin.joints.len())
                {
                    return Err(self.error(format_args!(
                        "mesh '{}' (skinned by node {} with {}) has vertex {v} bound to joint {} (JOINTS_0), but the skin has only {} joint(s); fix the joint indices or the skin's joint list",
                        mesh.name,
                        b.node,
                        skin.name,
                        vs.joints[k],
                        skin.joints.len()
                    )));
                }
            }
        }
        Ok(())
    }

    /// The file's animations: every channel checked, a broken one dropped with a warning (the
    /// scene still renders, and the rest of the animation still plays).
    pub(super) fn load_animations(&mut self) -> Result<()> {
        let doc = self.doc;
        for anim in doc.animations() {
            let name = anim
                .name()
                .map(str::to_owned)
                .unwrap_or_else(|| format!("animation {}", anim.index()));
            let mut channels = Vec::new();
            for (c, channel) in anim.channels().enumerate() {
                let who = format!(
                    "animation '{name}' channel {}",
                    self.pointers.file_index(anim.index(), c)
                );
                // The gltf crate's validator does not check a channel's target node, and its
                // Target::node() unwraps it: check before anything asks for it.
                let node = doc.as_json().animations[anim.index()].channels[c]
                    .target
                    .node
                    .value();
                if node >= doc.nodes().len() {
                    self.warn(format_args!(
                        "{who} targets node {node}, but the file has only {} node(s); the channel is ignored",
                        doc.nodes().len()
                    ));
                    continue;
                }
                match self.channel(&channel, &who) {
                    Ok(Some(ch)) => channels.push(ch),
                    Ok(None) => {}
                    Err(why) => self.warn(format_args!("{who} {why}; the channel is ignored")),
                }
            }
            // KHR_animation_pointer's channels, in the file's order among themselves (a later
            // channel on the same property wins, as with node channels).
            let pointed: Vec<_> = self
                .pointers
                .channels
                .iter()
                .filter(|p| p.animation == anim.index())
                .cloned()
                .collect();
            for pc in &pointed {
                let who = format!("animation '{name}' channel {}", pc.channel);
                // A mesh's default weights drive the nodes that draw it without their own.
                let expanded = self.expand_mesh_weights(pc);
                for pc in expanded.as_deref().unwrap_or(&[]) {
                    match self.pointer_channel(&anim, pc, &who) {
                        Ok(Some(ch)) => channels.push(ch),
                        Ok(None) => {}
                        Err(why) => self.warn(format_args!(
                            "{who} (KHR_animation_pointer) {why}; the channel is ignored"
                        )),
                    }
                }
                if let Err(why) = expanded {
                    self.warn(format_args!(
                        "{who} (KHR_animation_pointer) {why}; the channel is ignored"
                    ));
                }
            }
            let duration = channels
                .iter()
                .map(|c: &animation::Channel| c.sampler.end())
                .fold(0.0f32, f32::max);
            self.scene.rig.infos.push(animation::AnimationInfo {
                name: name.clone(),
                duration,
            });
            self.scene
                .rig
                .animations
                .push(animation::Animation { name, channels });
        }
        self.keep_pointed_at_rest();
        Ok(())
    }

    /// A sampler's keyframe times and values (`dims` per value) and its interpolation; the error
    /// (for `who`'s warning) says why they cannot be read.
    pub(super) fn keyframes(
        &self,
        sampler: &gltf::animation::Sampler<'a>,
        dims: Dimensions,
        who: &str,
    ) -> std::result::Result<(Vec<f32>, Vec<f32>, animation::Interpolation), String> {
        use gltf::animation::Interpolation as I;
        let read = |acc: gltf::Accessor, dims: Dimensions, what: &str| {
            accessor::read_f32(
                &acc,
                dims,
                self.buffers,
                &Use {
                    source: &self.label,
                    what: &format!("{who}, {what}"),
                },
            )
            .map_err(|e| format!("cannot be read: {e}"))
        };
        let times = read(sampler.input(), Dimensions::Scalar, "sampler input")?;
        let values = read(sampler.output(), dims, "sampler output")?;
        let interpolation = match sampler.interpolation() {
            I::Step => animation::Interpolation::Step,
            I::Linear => animation::Interpolation::Linear,
            I::CubicSpline => animation::Interpolation::CubicSpline,
        };
        Ok((times, values, interpolation))
    }

    pub(super) fn channel(
        &mut self,
        channel: &gltf::animation::Channel<'a>,
        who: &str,
    ) -> std::result::Result<Option<animation::Channel>, String> {
        use gltf::animation::Property;
        let target = channel.target();
        let node = target.node();
        let (path, width, dims) = match target.property() {
            Property::Translation => (animation::Path::Translation, 3, Dimensions::Vec3),
            Property::Rotation => (animation::Path::Rotation, 4, Dimensions::Vec4),
            Property::Scale => (animation::Path::Scale, 3, Dimensions::Vec3),
            Property::MorphTargetWeights => {
                let targets = self
                    .scene
                    .rig
                    .nodes
                    .get(node.index())
                    .map_or(0, |n| n.weights.len());
                if targets == 0 {
                    return Err(format!(
                        "animates the morph weights of node {}, which has no morph targets",
                        node.index()
                    ));
                }
                (animation::Path::Weights, targets, Dimensions::Scalar)
            }
        };
        if self
            .scene
            .rig
            .nodes
            .get(node.index())
            .is_some_and(|n| n.matrix.is_some())
            && path != animation::Path::Weights
        {
            return Err(format!(
                "animates node {}, which is given by a matrix (glTF allows channels only on nodes with translation, rotation and scale)",
                node.index()
            ));
        }
        let (times, values, interpolation) = self.keyframes(&channel.sampler(), dims, who)?;
        animation::Channel::new(node.index(), path, interpolation, times, values, width).map(Some)
    }
}
