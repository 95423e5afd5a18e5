//! The node tree: world transforms, instancing (EXT_mesh_gpu_instancing), shadow flags, and the draws, lights and cameras the nodes place.

use super::*;

impl<'a> Loader<'a> {
    // --- the node tree --------------------------------------------------------------------------

    pub(super) fn walk_nodes(&mut self) -> Result<()> {
        let doc = self.doc;
        let chosen = self.chosen_scene.and_then(|i| doc.scenes().nth(i));
        let picked = chosen.is_some();
        let roots: Vec<gltf::Node<'a>> = match chosen
            .or_else(|| doc.default_scene())
            .or_else(|| doc.scenes().next())
        {
            Some(scene) => {
                self.scene.gltf_scene = Some(scene.index());
                if doc.scenes().len() > 1 && !picked {
                    let name = scene
                        .name()
                        .map(|n| format!(" ('{n}')"))
                        .unwrap_or_default();
                    self.warn(format_args!(
                        "has {} scenes; weft renders scene {}{name}, the file's {} (--gltf-scene N or NAME picks another; `weft plan` lists them)",
                        doc.scenes().len(),
                        scene.index(),
                        if doc.default_scene().is_some() { "default" } else { "first" }
                    ));
                }
                scene.nodes().collect()
            }
            None => {
                // No scene: draw every node that is nobody's child.
                let mut is_child = vec![false; doc.nodes().len()];
                for node in doc.nodes() {
                    for child in node.children() {
                        if let Some(c) = is_child.get_mut(child.index()) {
                            *c = true;
                        }
                    }
                }
                let roots: Vec<_> = doc
                    .nodes()
                    .filter(|n| !is_child.get(n.index()).copied().unwrap_or(false))
                    .collect();
                if !roots.is_empty() {
                    self.warn("has no scenes; drawing every root node");
                }
                roots
            }
        };

        let mut visited = vec![false; doc.nodes().len()];
        let mut stack: Vec<(gltf::Node<'a>, Mat4, ShadowFlags)> = roots
            .into_iter()
            .rev()
            .map(|n| (n, Mat4::IDENTITY, ShadowFlags::DEFAULT))
            .collect();
        while let Some((node, parent, inherited)) = stack.pop() {
            let name = node
                .name()
                .map(str::to_owned)
                .unwrap_or_else(|| format!("node {}", node.index()));
            let who = format!("node '{name}' (node {})", node.index());
            match visited.get_mut(node.index()) {
                Some(seen) if !*seen => *seen = true,
                _ => {
                    return Err(self.error(format_args!(
                        "{who} is reached twice in the node hierarchy; glTF nodes must form trees (each node has at most one parent, no cycles): fix the \"children\" lists"
                    )))
                }
            }
            self.scene.rig.order.push(node.index());
            let world = parent * self.local_transform(&node, &who)?;
            if !world.is_finite() {
                return Err(self.error(format_args!(
                    "{who} has a world transform that is not finite (check its and its parents' translation, rotation, scale or matrix)"
                )));
            }
            let flags = self.node_shadow_flags(node.index(), inherited, &who)?;
            let instances = self.instance_transforms(&node, &who)?;
            if instances.is_some() && node.mesh().is_none() {
                self.warn(format_args!(
                    "{who} has {INSTANCING} but no mesh; the instances are ignored (the extension places a node's mesh)"
                ));
            }
            let instance_list = instances.clone().unwrap_or_else(|| vec![Mat4::IDENTITY]);
            if let (Some(list), Some(_)) = (&instances, node.mesh()) {
                self.scene.instanced_nodes += 1;
                self.scene.instances += list.len();
            }

            if let Some(mesh) = node.mesh() {
                let skin = node.skin().map(|s| s.index());
                let weights = self
                    .scene
                    .rig
                    .nodes
                    .get(node.index())
                    .map(|n| n.weights.clone())
                    .unwrap_or_default();
                for (id, &instance) in self
                    .mesh_ids(&mesh)?
                    .into_iter()
                    .flat_map(|id| instance_list.iter().map(move |m| (id, m)))
                {
                    let triangles = self.scene.meshes.get(id).map_or(0, |m| m.indices.len() / 3);
                    self.triangles_drawn = self.triangles_drawn.saturating_add(triangles as u64);
                    if self.triangles_drawn > MAX_DRAWN_TRIANGLES {
                        return Err(self.error(format_args!(
                            "{who} brings the triangles drawn to {}, more than weft's limit of {MAX_DRAWN_TRIANGLES} per frame; draw fewer copies of the mesh or decimate it",
                            self.triangles_drawn
                        )));
                    }
                    let deform = self.scene.rig.meshes.get(&id);
                    let targets = deform.map_or(0, |d| d.targets.len());
                    // A skin applies only to primitives with joints; the others follow the node.
                    let skin = skin.filter(|_| deform.is_some_and(|d| !d.skin.is_empty()));
                    self.scene.rig.draws.push(animation::DrawBinding {
                        draw: self.scene.draws.len(),
                        node: node.index(),
                        skin,
                        weights: (0..targets)
                            .map(|k| weights.get(k).copied().unwrap_or(0.0))
                            .collect(),
                        instance,
                    });
                    // A transmissive surface lets the light through: it casts no shadow (a
                    // shadow map holds opaque cover only).
                    let transmissive = self
                        .scene
                        .meshes
                        .get(id)
                        .and_then(|m| self.scene.materials.get(m.material))
                        .is_some_and(|m| m.transmission.as_ref().is_some_and(|t| t.factor > 0.0));
                    self.scene.draws.push(Draw {
                        cast_shadows: flags.cast && !transmissive,
                        receive_shadows: flags.receive,
                        ..Draw::new(id, world * instance)
                    });
                }
            }
            if let Some(camera) = node.camera() {
                let before = self.scene.cameras.len();
                self.place_camera(camera.index(), world, &who);
                if self.scene.cameras.len() > before {
                    self.scene.rig.cameras.push((before, node.index()));
                    self.scene.rig.camera_defs.push(camera.index());
                }
            }
            let light = doc
                .as_json()
                .nodes
                .get(node.index())
                .and_then(|n| n.extensions.as_ref())
                .and_then(|e| e.khr_lights_punctual.as_ref())
                .map(|l| l.light.value());
            if let Some(light) = light {
                let before = self.scene.lights.len();
                self.place_light(light, world, &who)?;
                if self.scene.lights.len() > before {
                    self.scene.rig.lights.push((before, node.index()));
                    self.scene.rig.light_defs.push(light);
                    let intensity = self.scene.lights[before].intensity;
                    self.scene.rig.light_intensity.push(intensity);
                }
            }
            for child in node.children().collect::<Vec<_>>().into_iter().rev() {
                stack.push((child, world, flags));
            }
        }
        Ok(())
    }

    /// EXT_mesh_gpu_instancing: the node's instance transforms (translation × rotation × scale,
    /// each from its accessor or the identity), None when the node has no such extension. The
    /// accessors must have one count; rotations are normalised (a zero or non-finite one, like a
    /// non-finite translation or scale, is an error naming the instance).
    pub(super) fn instance_transforms(
        &mut self,
        node: &gltf::Node<'a>,
        who: &str,
    ) -> Result<Option<Vec<Mat4>>> {
        let Some(ext) = node.extension_value(INSTANCING) else {
            return Ok(None);
        };
        let Some(attributes) = ext.get("attributes").and_then(|a| a.as_object()) else {
            return Err(self.error(format_args!(
                "{who}: {INSTANCING} has no \"attributes\" object; it needs TRANSLATION, ROTATION and/or SCALE accessors: fix or re-export the node"
            )));
        };
        let mut count: Option<(usize, &str)> = None;
        let mut columns: [Option<Vec<f32>>; 3] = [None, None, None];
        for (k, (key, dims, n)) in [
            ("TRANSLATION", Dimensions::Vec3, 3),
            ("ROTATION", Dimensions::Vec4, 4),
            ("SCALE", Dimensions::Vec3, 3),
        ]
        .into_iter()
        .enumerate()
        {
            let Some(value) = attributes.get(key) else {
                continue;
            };
            let Some(index) = value.as_u64().and_then(|i| usize::try_from(i).ok()) else {
                return Err(self.error(format_args!(
                    "{who}: {INSTANCING}.attributes.{key} is {}, not an accessor index: fix the node",
                    short_json(value)
                )));
            };
            let Some(acc) = self.doc.accessors().nth(index) else {
                return Err(self.error(format_args!(
                    "{who}: {INSTANCING}.attributes.{key} names accessor {index}, but the file has only {} accessor(s): fix the index",
                    self.doc.accessors().len()
                )));
            };
            if key == "ROTATION"
                && acc.data_type() != gltf::accessor::DataType::F32
                && !acc.normalized()
            {
                return Err(self.error(format_args!(
                    "{who}: {INSTANCING} ROTATION (accessor {index}) has component type {:?} without normalized; rotations are float or normalized byte or short quaternions: re-export the node",
                    acc.data_type()
                )));
            }
            let what = format!("{who}, {INSTANCING} {key}");
            let values = accessor::read_f32(
                &acc,
                dims,
                self.buffers,
                &Use {
                    source: &self.label,
                    what: &what,
                },
            )?;
            let c = values.len() / n;
            match count {
                Some((other, name)) if other != c => {
                    return Err(self.error(format_args!(
                        "{who}: {INSTANCING} {key} has {c} elements but {name} has {other}; every attribute has one element per instance: fix the accessors"
                    )))
                }
                _ => count = Some((c, key)),
            }
            columns[k] = Some(values);
        }
        let Some((count, _)) = count else {
            self.warn(format_args!(
                "{who}: {INSTANCING} has none of TRANSLATION, ROTATION and SCALE; the mesh is drawn once"
            ));
            return Ok(None);
        };
        let total = self.scene.instances.saturating_add(count);
        if total > MAX_INSTANCES {
            return Err(self.error(format_args!(
                "{who} brings the {INSTANCING} instances to {total}, more than weft's limit of {MAX_INSTANCES} (each is a draw of its own): use fewer instances"
            )));
        }
        let [t, r, s] = &columns;
        let mut out = Vec::with_capacity(count);
        for i in 0..count {
            let v3 = |c: &Option<Vec<f32>>, default: Vec3| {
                c.as_ref()
                    .map_or(default, |v| Vec3::new(v[3 * i], v[3 * i + 1], v[3 * i + 2]))
            };
            let translation = v3(t, Vec3::ZERO);
            let scale = v3(s, Vec3::ONE);
            let rotation = r.as_ref().map_or(Quat::IDENTITY, |v| {
                Quat::from_xyzw(v[4 * i], v[4 * i + 1], v[4 * i + 2], v[4 * i + 3])
            });
            if !(translation.is_finite() && scale.is_finite() && rotation.is_finite())
                || rotation.length_squared() < 1e-12
            {
                return Err(self.error(format_args!(
                    "{who}: {INSTANCING} instance {i} has translation {translation}, rotation {rotation} and scale {scale}; each must be finite and the rotation a unit quaternion: fix the accessors"
                )));
            }
            out.push(Mat4::from_scale_rotation_translation(
                scale,
                rotation.normalize(),
                translation,
            ));
        }
        Ok(Some(out))
    }

    /// The node's `extras.cast_shadows` and `extras.receive_shadows` (true or false), each
    /// `inherited` from the parent when absent (docs/scene-format.md).
    pub(super) fn node_shadow_flags(
        &mut self,
        index: usize,
        inherited: ShadowFlags,
        who: &str,
    ) -> Result<ShadowFlags> {
        let extras = self
            .doc
            .as_json()
            .nodes
            .get(index)
            .and_then(|n| extras_object(&n.extras));
        let Some(extras) = extras else {
            return Ok(inherited);
        };
        let flag = |key: &str, inherited: bool| -> Result<bool> {
            match extras.get(key) {
                None => Ok(inherited),
                Some(serde_json::Value::Bool(b)) => Ok(*b),
                Some(other) => Err(self.error(format_args!(
                    "{who} has extras.{key} = {}; it must be true or false (false: this node and its descendants {}; a descendant may set it again): fix the node's extras",
                    short_json(other),
                    if key == "cast_shadows" { "cast no shadows" } else { "are not darkened by shadows" },
                ))),
            }
        };
        let flags = ShadowFlags {
            cast: flag("cast_shadows", inherited.cast)?,
            receive: flag("receive_shadows", inherited.receive)?,
        };
        if extras.contains_key("shadows") {
            self.warn(format_args!(
                "{who} has extras.shadows, which weft ignores on a node: a light asks for shadows in its own extras (in the KHR_lights_punctual \"lights\" list), and a node sets extras.cast_shadows / extras.receive_shadows"
            ));
        }
        Ok(flags)
    }

    pub(super) fn local_transform(&self, node: &gltf::Node<'a>, who: &str) -> Result<Mat4> {
        Ok(match node.transform() {
            gltf::scene::Transform::Matrix { matrix } => Mat4::from_cols_array_2d(&matrix),
            gltf::scene::Transform::Decomposed {
                translation,
                rotation,
                scale,
            } => {
                let q = Quat::from_array(rotation);
                // glTF requires unit quaternions; exporters round, so normalise, but a zero one is wrong.
                let q = if q.length_squared() > 1e-12 && q.is_finite() {
                    q.normalize()
                } else {
                    return Err(self.error(format_args!(
                        "{who} has the rotation {rotation:?}, which is not a unit quaternion; set it to [x, y, z, w] of length 1 ([0, 0, 0, 1] for none)"
                    )));
                };
                Mat4::from_scale_rotation_translation(Vec3::from(scale), q, Vec3::from(translation))
            }
        })
    }

    pub(super) fn place_light(&mut self, index: usize, world: Mat4, who: &str) -> Result<()> {
        let Some(def) = self.lights.get(index) else {
            return Err(self.error(format_args!(
                "{who} refers to light {index}, which does not exist; fix the node's KHR_lights_punctual.light"
            )));
        };
        let position = world.w_axis.truncate();
        let Some(direction) = (world * Vec4::new(0.0, 0.0, -1.0, 0.0))
            .truncate()
            .try_normalize()
        else {
            let name = def.name.clone();
            self.warn(format_args!(
                "{who} scales light '{name}' to nothing, so it has no direction; the light is skipped"
            ));
            return Ok(());
        };
        self.scene.lights.push(Light {
            name: def.name.clone(),
            kind: def.kind,
            color: def.color,
            intensity: def.intensity,
            range: def.range,
            position,
            direction,
            shadow: def.shadow,
        });
        Ok(())
    }

    pub(super) fn place_camera(&mut self, index: usize, world: Mat4, who: &str) {
        let Some(Some(def)) = self.cameras.get(index) else {
            return;
        };
        // The view is the inverse of the node's rigid motion: scale (even mirroring) is removed,
        // keeping the view direction (-Z) and the up direction (+Y) of the node.
        let Some(mut camera) = animation::placed_camera(
            def.name.clone(),
            world,
            def.yfov,
            def.znear,
            def.zfar,
            def.aspect_ratio,
        ) else {
            let name = def.name.clone();
            self.warn(format_args!(
                "{who} scales camera '{name}' to nothing, so it has no orientation; the camera is skipped"
            ));
            return;
        };
        camera.orthographic = def.orthographic;
        self.scene.cameras.push(camera);
    }
}
