//! KHR_animation_pointer: animation channels whose target is a JSON pointer to a property of a
//! node, a material, a light or a camera instead of a node's transform.
//!
//! The gltf crate's animation schema predates the extension (a channel must name a `node` and a
//! path among translation, rotation, scale and weights), so such a file would be refused as
//! invalid: the pointer channels are taken out of the JSON before the crate reads it
//! ([`take_channels`]) and read here, with the same sampler checks as every channel
//! ([`animation::Channel::new`]). A pointer weft cannot follow (a texture transform, a mesh's
//! default weights, an extension weft does not read) is a warning naming it; the file still
//! renders and the rest of the animation still plays.

use super::*;
use animation::{CameraProperty, LightProperty, MaterialProperty};

/// A channel whose target is a KHR_animation_pointer.
#[derive(Clone, Debug)]
pub(super) struct PointerChannel {
    pub animation: usize,
    /// Its index among the animation's channels in the file.
    pub channel: usize,
    /// The JSON pointer (None: the channel's path is "pointer" but it has none).
    pub pointer: Option<String>,
    /// Its sampler (an index into the animation's samplers; None: missing or not an index).
    pub sampler: Option<usize>,
}

/// What [`take_channels`] took out of a file.
#[derive(Clone, Debug, Default)]
pub(super) struct PointerChannels {
    pub channels: Vec<PointerChannel>,
    /// Per animation: the file's index of each channel left for the gltf crate, so messages
    /// about them name the channel the file has.
    pub kept: Vec<Vec<usize>>,
}

impl PointerChannels {
    /// The file's index of channel `c` of animation `a` as the gltf crate sees it.
    pub fn file_index(&self, a: usize, c: usize) -> usize {
        self.kept
            .get(a)
            .and_then(|k| k.get(c))
            .copied()
            .unwrap_or(c)
    }
}

/// Takes the channels whose target path is "pointer" out of the glTF JSON `text`: the JSON
/// without them, and the channels. None when the text does not mention the extension or does
/// not parse as JSON (the caller's own parse then says why).
pub(super) fn take_channels(text: &[u8]) -> Option<(Vec<u8>, PointerChannels)> {
    const NAME: &[u8] = b"KHR_animation_pointer";
    if !text.windows(NAME.len()).any(|w| w == NAME) {
        return None;
    }
    let mut root: serde_json::Value = serde_json::from_slice(text).ok()?;
    let animations = root.get_mut("animations")?.as_array_mut()?;
    let mut out = PointerChannels::default();
    for (a, anim) in animations.iter_mut().enumerate() {
        let mut kept = Vec::new();
        if let Some(channels) = anim.get_mut("channels").and_then(|c| c.as_array_mut()) {
            let all = std::mem::take(channels);
            for (c, channel) in all.into_iter().enumerate() {
                let target = channel.get("target");
                let is_pointer =
                    target.and_then(|t| t.get("path")).and_then(|p| p.as_str()) == Some("pointer");
                if !is_pointer {
                    kept.push(c);
                    channels.push(channel);
                    continue;
                }
                let pointer = target
                    .and_then(|t| t.get("extensions"))
                    .and_then(|e| e.get("KHR_animation_pointer"))
                    .and_then(|p| p.get("pointer"))
                    .and_then(|p| p.as_str())
                    .map(str::to_owned);
                let sampler = channel
                    .get("sampler")
                    .and_then(|s| s.as_u64())
                    .and_then(|s| usize::try_from(s).ok());
                out.channels.push(PointerChannel {
                    animation: a,
                    channel: c,
                    pointer,
                    sampler,
                });
            }
        }
        out.kept.push(kept);
    }
    if out.channels.is_empty() {
        return None;
    }
    let text = serde_json::to_vec(&root).ok()?;
    Some((text, out))
}

/// A JSON pointer's reference tokens (RFC 6901: `~1` is `/`, `~0` is `~`), or None when it does
/// not start with `/`.
fn tokens(pointer: &str) -> Option<Vec<String>> {
    let rest = pointer.strip_prefix('/')?;
    Some(
        rest.split('/')
            .map(|t| t.replace("~1", "/").replace("~0", "~"))
            .collect(),
    )
}

/// What a pointer names: a path of a node, material, light or camera, the index, and the width
/// of its value.
fn resolve(pointer: &str) -> std::result::Result<(animation::Path, usize, usize), String> {
    let unsupported = || {
        format!(
            "points at '{pointer}', which weft does not animate (it animates nodes' translation, rotation, scale, weights and KHR_node_visibility, meshes' default weights, materials' factors and texture transforms, lights' colour, intensity, range and cones, and cameras' projections)"
        )
    };
    let t = tokens(pointer).ok_or_else(|| {
        format!("has the pointer '{pointer}', which is not a JSON pointer (it must start with '/')")
    })?;
    let index = |s: &str| -> std::result::Result<usize, String> {
        s.parse::<usize>().map_err(|_| {
            format!(
                "has the pointer '{pointer}', whose '{s}' is not an index into the list it names"
            )
        })
    };
    match t.iter().map(String::as_str).collect::<Vec<_>>().as_slice() {
        ["nodes", i, "extensions", "KHR_node_visibility", "visible"] => {
            Ok((animation::Path::Visible, index(i)?, 1))
        }
        ["nodes", i, p] => {
            let path = match *p {
                "translation" => (animation::Path::Translation, 3),
                "rotation" => (animation::Path::Rotation, 4),
                "scale" => (animation::Path::Scale, 3),
                "weights" => (animation::Path::Weights, 0),
                _ => return Err(unsupported()),
            };
            Ok((path.0, index(i)?, path.1))
        }
        ["materials", i, rest @ ..] => {
            let (p, width) =
                MaterialProperty::from_path(&rest.join("/")).ok_or_else(unsupported)?;
            Ok((animation::Path::Material(p), index(i)?, width))
        }
        ["extensions", "KHR_lights_punctual", "lights", i, rest @ ..] => {
            let (p, width) = LightProperty::from_path(&rest.join("/")).ok_or_else(unsupported)?;
            Ok((animation::Path::Light(p), index(i)?, width))
        }
        ["cameras", i, rest @ ..] => {
            let (p, _) = CameraProperty::from_path(&rest.join("/")).ok_or_else(unsupported)?;
            Ok((animation::Path::Camera(p), index(i)?, 1))
        }
        _ => Err(unsupported()),
    }
}

impl<'a> Loader<'a> {
    /// A channel on a mesh's default morph weights (`/meshes/M/weights`) as the channels on the
    /// weights of each node that draws mesh M without weights of its own (what the mesh's
    /// weights are the default of); any other channel as it is. The error says why such a
    /// channel drives nothing.
    pub(super) fn expand_mesh_weights(
        &self,
        pc: &PointerChannel,
    ) -> std::result::Result<Vec<PointerChannel>, String> {
        let Some(mesh) = pc
            .pointer
            .as_deref()
            .and_then(|p| p.strip_prefix("/meshes/"))
            .and_then(|p| p.strip_suffix("/weights"))
            .and_then(|m| m.parse::<usize>().ok())
        else {
            return Ok(vec![pc.clone()]);
        };
        let nodes: Vec<PointerChannel> = self
            .doc
            .nodes()
            .filter(|n| n.mesh().is_some_and(|m| m.index() == mesh) && n.weights().is_none())
            .map(|n| PointerChannel {
                pointer: Some(format!("/nodes/{}/weights", n.index())),
                ..pc.clone()
            })
            .collect();
        if nodes.is_empty() {
            return Err(format!(
                "animates the default weights of mesh {mesh}, but no node draws that mesh without weights of its own"
            ));
        }
        Ok(nodes)
    }

    /// Reads a pointer channel of animation `anim` (named `who` in messages); Ok(None) when it
    /// drives nothing the scene has. The error says why the channel is dropped.
    pub(super) fn pointer_channel(
        &mut self,
        anim: &gltf::Animation<'a>,
        pc: &PointerChannel,
        who: &str,
    ) -> std::result::Result<Option<animation::Channel>, String> {
        let pointer = pc.pointer.as_deref().ok_or_else(|| {
            "has the target path 'pointer' but no KHR_animation_pointer extension with a pointer".to_string()
        })?;
        let (path, target, width) = resolve(pointer)?;
        let doc = self.doc;
        let width = match path {
            animation::Path::Visible => {
                if target >= self.scene.rig.nodes.len() {
                    return Err(format!(
                        "points at node {target}, but the file has only {} node(s)",
                        doc.nodes().len()
                    ));
                }
                width
            }
            animation::Path::Translation
            | animation::Path::Rotation
            | animation::Path::Scale
            | animation::Path::Weights => {
                let Some(node) = self.scene.rig.nodes.get(target) else {
                    return Err(format!(
                        "points at node {target}, but the file has only {} node(s)",
                        doc.nodes().len()
                    ));
                };
                if node.matrix.is_some() && path != animation::Path::Weights {
                    return Err(format!(
                        "animates node {target}, which is given by a matrix (glTF allows channels only on nodes with translation, rotation and scale)"
                    ));
                }
                if path == animation::Path::Weights {
                    if node.weights.is_empty() {
                        return Err(format!(
                            "animates the morph weights of node {target}, which has no morph targets"
                        ));
                    }
                    node.weights.len()
                } else {
                    width
                }
            }
            animation::Path::Material(p) => {
                let Some(m) = self
                    .scene
                    .materials
                    .get(target)
                    .filter(|_| target < self.scene.file_materials)
                else {
                    return Err(format!(
                        "points at material {target}, but the file has only {} material(s)",
                        self.scene.file_materials
                    ));
                };
                if let Some(why) = p.missing_on(m) {
                    return Err(format!(
                        "points at '{pointer}', but {why} on material '{}'",
                        m.name
                    ));
                }
                width
            }
            animation::Path::Light(p) => {
                let Some(def) = self.lights.get(target) else {
                    return Err(format!(
                        "points at light {target}, but the file has only {} light(s)",
                        self.lights.len()
                    ));
                };
                let spot = matches!(def.kind, LightKind::Spot { .. });
                if matches!(p, LightProperty::InnerCone | LightProperty::OuterCone) && !spot {
                    return Err(format!(
                        "points at '{pointer}', but light '{}' is not a spot light",
                        def.name
                    ));
                }
                width
            }
            animation::Path::Camera(p) => {
                let Some(Some(def)) = self.cameras.get(target) else {
                    return Err(format!(
                        "points at camera {target}, which the file does not have (or which was skipped)"
                    ));
                };
                let perspective = pointer.split('/').nth(3) == Some("perspective");
                if perspective == def.orthographic.is_some() {
                    return Err(format!(
                        "points at '{pointer}', but camera {target} is {}",
                        if def.orthographic.is_some() {
                            "orthographic"
                        } else {
                            "a perspective camera"
                        }
                    ));
                }
                if p == CameraProperty::Zfar && def.zfar.is_none() {
                    return Err(format!(
                        "points at '{pointer}', but camera {target} has no far plane (it is infinite)"
                    ));
                }
                width
            }
        };
        let Some(sampler) = pc.sampler.and_then(|s| anim.samplers().nth(s)) else {
            return Err(format!(
                "uses a sampler the animation does not have (it has {})",
                anim.samplers().count()
            ));
        };
        let dims = match (path, width) {
            (animation::Path::Weights, _) | (_, 1) => Dimensions::Scalar,
            (_, 2) => Dimensions::Vec2,
            (_, 3) => Dimensions::Vec3,
            _ => Dimensions::Vec4,
        };
        let (times, values, interpolation) = self.keyframes(&sampler, dims, who)?;
        animation::Channel::new(target, path, interpolation, times, values, width).map(Some)
    }

    /// Keeps at rest what the loaded pointer channels drive (materials, with their emissive
    /// factor and strength, and their unlit copies; lights; cameras), for [`Scene::pose`].
    pub(super) fn keep_pointed_at_rest(&mut self) {
        let mut pointed = animation::Pointed::default();
        let doc = self.doc;
        let rig = &self.scene.rig;
        for channel in rig.animations.iter().flat_map(|a| &a.channels) {
            match channel.path {
                animation::Path::Material(_) => {
                    let i = channel.node;
                    if let (Some(m), Some(gm), Some(frame), Some(transforms)) = (
                        self.scene.materials.get(i),
                        doc.materials().nth(i),
                        self.material_uv.get(i),
                        self.slot_transforms.get(i),
                    ) {
                        pointed.materials.entry(i).or_insert_with(|| {
                            let state = animation::MaterialState {
                                emissive: gm.emissive_factor(),
                                strength: gm.emissive_strength().unwrap_or(1.0),
                                transforms: *transforms,
                                frame_inverse: frame
                                    .inverse()
                                    .unwrap_or(UvTransform::IDENTITY.affine()),
                                moved: 0,
                            };
                            (m.clone(), state)
                        });
                    }
                }
                animation::Path::Light(_) => {
                    for (k, &(l, _)) in rig.lights.iter().enumerate() {
                        if rig.light_defs.get(k) == Some(&channel.node) {
                            if let Some(light) = self.scene.lights.get(l) {
                                pointed.lights.entry(l).or_insert_with(|| light.clone());
                            }
                        }
                    }
                }
                animation::Path::Camera(_) => {
                    for (k, &(c, _)) in rig.cameras.iter().enumerate() {
                        if rig.camera_defs.get(k) == Some(&channel.node) {
                            if let Some(camera) = self.scene.cameras.get(c) {
                                pointed.cameras.entry(c).or_insert_with(|| camera.clone());
                            }
                        }
                    }
                }
                _ => {}
            }
        }
        if pointed.materials.is_empty() && pointed.lights.is_empty() && pointed.cameras.is_empty() {
            return;
        }
        pointed.copies = self
            .unlit_copies
            .iter()
            .filter(|(o, _)| pointed.materials.contains_key(o))
            .map(|(&o, &c)| (o, c))
            .collect();
        pointed.copies.sort_unstable();
        self.scene.rig.pointed = Some(pointed);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pointers_resolve_to_the_property_they_name() {
        use animation::Path;
        assert_eq!(
            resolve("/nodes/3/rotation").unwrap(),
            (Path::Rotation, 3, 4)
        );
        assert_eq!(
            resolve("/materials/0/pbrMetallicRoughness/baseColorFactor").unwrap(),
            (Path::Material(MaterialProperty::BaseColor), 0, 4)
        );
        assert_eq!(
            resolve("/materials/2/extensions/KHR_materials_emissive_strength/emissiveStrength")
                .unwrap(),
            (Path::Material(MaterialProperty::EmissiveStrength), 2, 1)
        );
        assert_eq!(
            resolve("/extensions/KHR_lights_punctual/lights/1/spot/outerConeAngle").unwrap(),
            (Path::Light(LightProperty::OuterCone), 1, 1)
        );
        assert_eq!(
            resolve("/cameras/0/perspective/yfov").unwrap(),
            (Path::Camera(CameraProperty::Yfov), 0, 1)
        );
        assert_eq!(
            resolve("/materials/1/extensions/KHR_materials_sheen/sheenColorTexture/extensions/KHR_texture_transform/offset")
                .unwrap(),
            (Path::Material(MaterialProperty::TextureOffset(crate::scene::TextureSlot::SheenColor)), 1, 2)
        );
        let why =
            resolve("/materials/0/pbrMetallicRoughness/baseColorTexture/texCoord").unwrap_err();
        assert!(why.contains("does not animate"), "{why}");
        assert!(resolve("materials/0/alphaCutoff")
            .unwrap_err()
            .contains("must start with '/'"));
        assert!(resolve("/materials/x/alphaCutoff")
            .unwrap_err()
            .contains("not an index"));
    }

    #[test]
    fn pointer_tokens_unescape() {
        assert_eq!(tokens("/a~1b/c~0d").unwrap(), vec!["a/b", "c~d"]);
    }

    #[test]
    fn pointer_channels_are_taken_out_and_the_rest_keep_their_file_index() {
        let text = br#"{"asset":{"version":"2.0"},"animations":[{"channels":[
            {"sampler":0,"target":{"node":0,"path":"translation"}},
            {"sampler":1,"target":{"path":"pointer","extensions":{"KHR_animation_pointer":{"pointer":"/materials/0/alphaCutoff"}}}},
            {"sampler":0,"target":{"node":1,"path":"scale"}}],"samplers":[]}]}"#;
        let (json, taken) = take_channels(text).expect("a pointer channel");
        let v: serde_json::Value = serde_json::from_slice(&json).unwrap();
        assert_eq!(v["animations"][0]["channels"].as_array().unwrap().len(), 2);
        assert_eq!(taken.channels.len(), 1);
        assert_eq!(taken.channels[0].channel, 1);
        assert_eq!(taken.channels[0].sampler, Some(1));
        assert_eq!(
            taken.channels[0].pointer.as_deref(),
            Some("/materials/0/alphaCutoff")
        );
        assert_eq!(taken.file_index(0, 1), 2);
        assert!(take_channels(br#"{"asset":{"version":"2.0"}}"#).is_none());
    }
}
