//! The meshes: primitives (Draco-compressed or not) into triangles, lines and points, vertex colours, morph targets and skin weights.

use super::*;

impl<'a> Loader<'a> {
    // --- meshes ---------------------------------------------------------------------------------

    /// The scene meshes of glTF mesh `mesh` (one per triangle primitive), built on first use.
    pub(super) fn mesh_ids(&mut self, mesh: &gltf::Mesh<'a>) -> Result<Vec<usize>> {
        if let Some(Some(ids)) = self.mesh_ids.get(mesh.index()) {
            return Ok(ids.clone());
        }
        let name = mesh
            .name()
            .map(str::to_owned)
            .unwrap_or_else(|| format!("mesh {}", mesh.index()));
        let several = mesh.primitives().len() > 1;
        let mut ids = Vec::new();
        for prim in mesh.primitives() {
            let who = format!("mesh '{name}' primitive {}", prim.index());
            let mesh_name = if several {
                format!("{name} (primitive {})", prim.index())
            } else {
                name.clone()
            };
            if let Some((m, deform)) = self.primitive(&prim, &who, mesh_name)? {
                self.scene.meshes.push(m);
                let id = self.scene.meshes.len() - 1;
                if let Some(deform) = deform {
                    self.scene.rig.meshes.insert(id, deform);
                }
                ids.push(id);
            }
        }
        if let Some(slot) = self.mesh_ids.get_mut(mesh.index()) {
            *slot = Some(ids.clone());
        }
        Ok(ids)
    }

    /// The glTF material of a primitive: its variant's mapping when a variant was chosen and the
    /// primitive maps it, else its own.
    pub(super) fn gltf_material(&self, prim: &gltf::Primitive<'a>) -> Result<Option<usize>> {
        if let (Some((variant, count)), Some(ext)) =
            (self.variant, prim.extension_value(material_ext::VARIANTS))
        {
            if let Some(m) =
                material_ext::mapped_material(ext, variant, count).map_err(|e| self.error(e))?
            {
                // The file's materials, not the loader's (its default material may follow them).
                if m >= self.doc.materials().len() {
                    return Err(self.error(format_args!(
                        "{}.mappings names material {m}, but the file has {} materials; fix the mapping",
                        material_ext::VARIANTS,
                        self.doc.materials().len()
                    )));
                }
                return Ok(Some(m));
            }
        }
        Ok(prim.material().index())
    }

    pub(super) fn material_index(&mut self, prim: &gltf::Primitive<'a>) -> Result<usize> {
        Ok(match self.gltf_material(prim)? {
            Some(i) => i,
            None => *self.default_material.get_or_insert_with(|| {
                self.scene.materials.push(Material::default());
                self.scene.materials.len() - 1
            }),
        })
    }

    /// `value` (a material extension), or None with a warning saying `why` where the material
    /// is woven (`on_fabric`): the extensions the woven model does not combine with yet.
    pub(super) fn not_on_fabric<T>(
        &mut self,
        value: Option<T>,
        on_fabric: bool,
        who: &str,
        extension: &str,
        why: &str,
    ) -> Option<T> {
        if value.is_some() && on_fabric {
            self.warn(format_args!(
                "{who} has both {extension} and {FABRIC_EXTENSION}; {why}"
            ));
            return None;
        }
        value
    }

    /// An unlit copy of material `index` (made once): what points and lines without normals are
    /// drawn with. A material that is unlit already is its own copy.
    pub(super) fn unlit_copy(&mut self, index: usize) -> usize {
        if self.scene.materials.get(index).is_none_or(|m| m.unlit) {
            return index;
        }
        if let Some(&copy) = self.unlit_copies.get(&index) {
            return copy;
        }
        let m = &self.scene.materials[index];
        let copy = Material {
            name: format!("{} (unlit: points and lines without normals)", m.name),
            unlit: true,
            fabric: None,
            ..m.clone()
        };
        self.scene.materials.push(copy);
        let copy = self.scene.materials.len() - 1;
        self.unlit_copies.insert(index, copy);
        copy
    }

    /// Decodes a primitive's KHR_draco_mesh_compression bitstream.
    pub(super) fn draco(&self, ext: &serde_json::Value, who: &str) -> Result<DracoPrimitive> {
        let view_index = ext
            .get("bufferView")
            .and_then(serde_json::Value::as_u64)
            .ok_or_else(|| {
                self.error(format_args!(
                    "{who}: {DRACO} has no bufferView index; fix the file or export it without Draco compression"
                ))
            })? as usize;
        let view = self.doc.views().nth(view_index).ok_or_else(|| {
            self.error(format_args!(
                "{who}: {DRACO} names bufferView {view_index}, but the file has {}; fix the file",
                self.doc.views().len()
            ))
        })?;
        let bytes = self
            .buffers
            .get(view.buffer().index())
            .and_then(|b| b.get(view.offset()..view.offset().checked_add(view.length())?))
            .ok_or_else(|| {
                self.error(format_args!(
                    "{who}: {DRACO}'s bufferView {view_index} (bytes {}..{} of buffer {}) lies outside its buffer; the file is truncated or broken: re-export it",
                    view.offset(),
                    view.offset().saturating_add(view.length()),
                    view.buffer().index()
                ))
            })?;
        let mut ids = HashMap::new();
        if let Some(map) = ext.get("attributes").and_then(serde_json::Value::as_object) {
            for (name, id) in map {
                let id = id
                    .as_u64()
                    .and_then(|i| u32::try_from(i).ok())
                    .ok_or_else(|| {
                        self.error(format_args!(
                        "{who}: {DRACO}.attributes.{name} is not a Draco attribute id; fix the file"
                    ))
                    })?;
                if !DRACO_SEMANTICS.contains(&name.as_str()) {
                    return Err(self.error(format_args!(
                        "{who}: its {name} attribute is Draco-compressed, which weft reads for {} only; export the file without Draco compression (or without {name})",
                        DRACO_SEMANTICS.join(", ")
                    )));
                }
                ids.insert(name.clone(), id);
            }
        }
        if !ids.contains_key("POSITION") {
            return Err(self.error(format_args!(
                "{who}: {DRACO} does not map POSITION; every primitive needs one: re-export the file"
            )));
        }
        let mut mesh = draco_core::Mesh::new();
        draco_core::MeshDecoder::new()
            .decode(&mut draco_core::DecoderBuffer::new(bytes), &mut mesh)
            .map_err(|e| {
                self.error(format_args!(
                    "{who}: its Draco-compressed data (bufferView {view_index}, {} bytes) does not decode ({e}); the file is damaged: re-export it, or export it without Draco compression",
                    bytes.len()
                ))
            })?;
        Ok(DracoPrimitive { mesh, ids })
    }

    pub(super) fn primitive(
        &mut self,
        prim: &gltf::Primitive<'a>,
        who: &str,
        name: String,
    ) -> Result<Option<(Mesh, Option<MeshDeform>)>> {
        let buffers = self.buffers;
        let draco = match prim.extension_value(DRACO) {
            Some(ext) => Some(self.draco(ext, who)?),
            None => None,
        };
        let label = &self.label;
        let read = |semantic: &Semantic, dims: Dimensions| -> Result<Option<(usize, Vec<f32>)>> {
            if let Some(d) = &draco {
                if let Some(&id) = d.ids.get(&semantic.to_string()) {
                    let att = d.mesh.attribute_by_unique_id(id).ok_or_else(|| {
                        Error::input(format!("{label}: {}", format_args!(
                            "{who}: {DRACO} maps {} to Draco attribute {id}, which its compressed data does not have; re-export the file",
                            semantic.to_string()
                        )))
                    })?;
                    let n = match dims {
                        Dimensions::Scalar => 1,
                        Dimensions::Vec2 => 2,
                        Dimensions::Vec3 => 3,
                        _ => 4,
                    };
                    let mut values = att.read_f32s(d.mesh.num_points(), n);
                    if att.normalized() {
                        use draco_core::DataType as T;
                        let (scale, min) = match att.data_type() {
                            T::Uint8 => (1.0 / 255.0, 0.0),
                            T::Uint16 => (1.0 / 65535.0, 0.0),
                            T::Int8 => (1.0 / 127.0, -1.0),
                            T::Int16 => (1.0 / 32767.0, -1.0),
                            _ => (1.0, f32::MIN),
                        };
                        for v in &mut values {
                            *v = (*v * scale).max(min);
                        }
                    }
                    if values.iter().any(|v| !v.is_finite()) {
                        return Err(Error::input(format!("{label}: {}", format_args!(
                            "{who}: the Draco-compressed {} holds values that are not finite numbers; re-export the file",
                            semantic.to_string()
                        ))));
                    }
                    let acc = prim.get(semantic).map_or(usize::MAX, |a| a.index());
                    return Ok(Some((acc, values)));
                }
            }
            match prim.get(semantic) {
                None => Ok(None),
                Some(acc) => {
                    let what = format!("{who}, attribute {}", semantic.to_string());
                    let values = accessor::read_f32(
                        &acc,
                        dims,
                        buffers,
                        &Use {
                            source: &self.label,
                            what: &what,
                        },
                    )?;
                    Ok(Some((acc.index(), values)))
                }
            }
        };
        // Counted before reading, so the limit also bounds the time spent on primitives that turn
        // out to have no triangles.
        let claimed = prim.get(&Semantic::Positions).map_or(0, |a| a.count());
        self.vertices_read = self.vertices_read.saturating_add(claimed);
        if self.vertices_read > MAX_VERTICES {
            return Err(self.error(format_args!(
                "{who} brings the vertices read to {}, more than weft's limit of {MAX_VERTICES} for a scene (primitives that share an accessor count it each time); decimate or split the scene, or give primitives their own, smaller accessors",
                self.vertices_read
            )));
        }
        let (pos_accessor, positions) = read(&Semantic::Positions, Dimensions::Vec3)?.ok_or_else(|| {
            self.error(format_args!("{who} has no POSITION attribute; every primitive needs one: re-export the mesh"))
        })?;
        let count = positions.len() / 3;
        if u32::try_from(count).is_err() {
            return Err(self.error(format_args!(
                "{who} has {count} vertices; weft supports at most 2^32 - 1 per primitive: split the mesh"
            )));
        }
        let normals = read(&Semantic::Normals, Dimensions::Vec3)?;
        let tangents = read(&Semantic::Tangents, Dimensions::Vec4)?;
        let uvs = read(&Semantic::TexCoords(0), Dimensions::Vec2)?;
        // TEXCOORD_1 only when a texture of the primitive's material reads it.
        let wants_uv1 = self
            .gltf_material(prim)?
            .and_then(|m| self.scene.materials.get(m))
            .is_some_and(|m| m.uv.iter().any(|s| s.set == 1));
        let uvs1 = if wants_uv1 {
            let uvs1 = read(&Semantic::TexCoords(1), Dimensions::Vec2)?;
            if uvs1.is_none() {
                self.warn(format_args!(
                    "{who}'s material samples a texture with TEXCOORD_1, but the primitive has no TEXCOORD_1; it is sampled at (0, 0): add the second UV set or point the texture at texCoord 0"
                ));
            }
            uvs1
        } else {
            None
        };
        for (semantic, attr, n) in [
            ("NORMAL", &normals, 3),
            ("TANGENT", &tangents, 4),
            ("TEXCOORD_0", &uvs, 2),
            ("TEXCOORD_1", &uvs1, 2),
        ] {
            if let Some((acc, values)) = attr {
                if values.len() / n != count {
                    return Err(self.error(format_args!(
                        "{who}: attribute {semantic} (accessor {acc}) has {} elements but POSITION (accessor {pos_accessor}) has {count}; all attributes of a primitive must have the same count: re-export the mesh",
                        values.len() / n
                    )));
                }
            }
        }
        let mut colors = self.vertex_colors(prim, who, count)?;
        let mut deform = self.primitive_deform(prim, who, count)?;

        let mut indices = match (&draco, prim.indices()) {
            (Some(d), _) => {
                let faces = d.mesh.num_faces();
                self.indices_read = self.indices_read.saturating_add(faces.saturating_mul(3));
                if self.indices_read > MAX_INDICES {
                    return Err(self.error(format_args!(
                        "{who} brings the indices read to {}, more than weft's limit of {MAX_INDICES} ({} million triangles) for a scene; decimate the meshes or split the scene",
                        self.indices_read,
                        MAX_INDICES / 3 / 1_000_000
                    )));
                }
                let mut out = Vec::with_capacity(faces * 3);
                for f in 0..faces {
                    for p in d.mesh.face(draco_core::FaceIndex(f as u32)) {
                        if p.0 as usize >= count {
                            return Err(self.error(format_args!(
                                "{who}: its Draco-compressed face {f} names point {}, but the primitive has only {count} points; re-export the file",
                                p.0
                            )));
                        }
                        out.push(p.0);
                    }
                }
                out
            }
            (None, Some(acc)) => {
                let what = format!("{who}, indices");
                self.indices_read = self.indices_read.saturating_add(acc.count());
                if self.indices_read > MAX_INDICES {
                    return Err(self.error(format_args!(
                        "{who} brings the indices read to {}, more than weft's limit of {MAX_INDICES} ({} million triangles) for a scene; decimate the meshes or split the scene",
                        self.indices_read,
                        MAX_INDICES / 3 / 1_000_000
                    )));
                }
                let indices = accessor::read_u32(
                    &acc,
                    buffers,
                    &Use {
                        source: &self.label,
                        what: &what,
                    },
                )?;
                if let Some((k, &i)) = indices
                    .iter()
                    .enumerate()
                    .find(|(_, &i)| i as usize >= count)
                {
                    return Err(self.error(format_args!(
                        "{who}: index accessor {} holds index {i} at position {k}, but the primitive has only {count} vertices (POSITION accessor {pos_accessor}); fix the indices or re-export the mesh",
                        acc.index()
                    )));
                }
                indices
            }
            (None, None) => (0..count as u32).collect(),
        };
        let topology = match prim.mode() {
            Mode::Points => Topology::Points,
            Mode::Lines | Mode::LineLoop | Mode::LineStrip => Topology::Lines,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan => Topology::Triangles,
        };
        match prim.mode() {
            Mode::TriangleStrip => indices = strip_to_list(&indices),
            Mode::TriangleFan => indices = fan_to_list(&indices),
            Mode::LineStrip => indices = line_strip_to_list(&indices, false),
            Mode::LineLoop => indices = line_strip_to_list(&indices, true),
            _ => {}
        }
        let arity = topology.arity();
        let unit = match topology {
            Topology::Triangles => "triangles",
            Topology::Lines => "line segments",
            Topology::Points => "points",
        };
        if indices.len() % arity != 0 {
            self.warn(format_args!(
                "{who} has {} indices, not a multiple of {arity}; the last {} are ignored",
                indices.len(),
                indices.len() % arity
            ));
            indices.truncate(indices.len() / arity * arity);
        }
        if indices.is_empty() {
            self.warn(format_args!("{who} has no {unit}; skipped"));
            return Ok(None);
        }

        // Positions: a non-finite vertex in a triangle breaks rasterisation, bounds and tangents.
        let position = |v: usize| [positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]];
        if let Some((corner, &v)) = indices
            .iter()
            .enumerate()
            .find(|(_, &v)| !position(v as usize).iter().all(|c| c.is_finite()))
        {
            return Err(self.error(format_args!(
                "{who}: vertex {v} of {} {} has the non-finite position {:?} (POSITION accessor {pos_accessor}); fix or delete that vertex in your modelling tool and re-export",
                &unit[..unit.len() - 1],
                corner / arity,
                position(v as usize)
            )));
        }

        let mut vertices: Vec<Vertex> = (0..count)
            .map(|v| Vertex {
                // Vertices no triangle uses are never drawn; keep them finite all the same.
                position: position(v).map(|c| if c.is_finite() { c } else { 0.0 }),
                normal: normals
                    .as_ref()
                    .map_or([0.0; 3], |(_, n)| [n[3 * v], n[3 * v + 1], n[3 * v + 2]]),
                tangent: tangents.as_ref().map_or([0.0; 4], |(_, t)| {
                    [t[4 * v], t[4 * v + 1], t[4 * v + 2], t[4 * v + 3]]
                }),
                uv: uvs
                    .as_ref()
                    .map_or([0.0; 2], |(_, t)| [t[2 * v], t[2 * v + 1]]),
                uv1: uvs1
                    .as_ref()
                    .map(|(_, t)| [t[2 * v], t[2 * v + 1]])
                    .filter(|uv| uv.iter().all(|c| c.is_finite()))
                    .unwrap_or([0.0; 2]),
            })
            .collect();

        let mut material = self.material_index(prim)?;
        if topology != Topology::Triangles && normals.is_none() {
            // glTF: points and lines without normals are drawn without lighting (their base
            // colour), through an unlit copy of their material.
            material = self.unlit_copy(material);
        }
        if topology != Topology::Triangles
            && self
                .scene
                .materials
                .get(material)
                .is_some_and(|m| m.needs_forward())
        {
            self.warn(format_args!(
                "{who}: {unit} are drawn opaque by the G-buffer pass; their material's alphaMode BLEND, transmission, clear coat, diffuse transmission or thin film is not applied to them"
            ));
        }
        let uv_transform = self
            .gltf_material(prim)?
            .and_then(|m| self.material_uv.get(m))
            .copied()
            .unwrap_or(UvTransform::IDENTITY);

        if uvs.is_some() {
            // The transform first: finite coordinates through a finite transform can still
            // overflow, and get the same repair as the file's own non-finite ones.
            let finite = |v: &Vertex| v.uv.iter().all(|c| c.is_finite());
            let in_file = vertices.iter().filter(|v| !finite(v)).count();
            if uv_transform != UvTransform::IDENTITY {
                for v in vertices.iter_mut() {
                    v.uv = uv_transform.apply(v.uv);
                }
            }
            let bad = vertices.iter().filter(|v| !finite(v)).count();
            if bad > 0 {
                let made = if bad > in_file {
                    format!(
                        " ({} of them made so by its material's KHR_texture_transform, whose result overflows 32-bit floating point)",
                        bad - in_file
                    )
                } else {
                    String::new()
                };
                self.warn(format_args!(
                    "{who} has {bad} non-finite texture coordinate(s){made}; replaced by (0, 0)"
                ));
                for v in vertices.iter_mut().filter(|v| !finite(v)) {
                    v.uv = [0.0, 0.0];
                }
            }
        } else {
            let m = self.scene.materials.get(material);
            let needs_uvs = m.is_some_and(|m| {
                m.fabric.is_some()
                    || m.base_color_texture.is_some()
                    || m.metallic_roughness_texture.is_some()
                    || m.normal_texture.is_some()
                    || m.emissive_texture.is_some()
            });
            if needs_uvs {
                let mname = m.map(|m| m.name.clone()).unwrap_or_default();
                self.warn(format_args!(
                    "{who} has no texture coordinates (TEXCOORD_0) but its material '{mname}' has textures or a weave; they will look flat: add UVs to the mesh"
                ));
            }
        }

        // Each slot's own transform runs in the shader, on these coordinates: one that
        // overflows on them would make the surface black.
        if let Some(m) = self.scene.materials.get_mut(material) {
            let slots: Vec<usize> = (0..m.uv.len())
                .filter(|&k| m.uv[k].overflows_on(&vertices))
                .collect();
            for &k in &slots {
                m.uv[k] = SlotUv::IDENTITY;
            }
            if !slots.is_empty() {
                let names: Vec<&str> = slots.iter().map(|&k| TextureSlot::NAMES[k]).collect();
                let mname = m.name.clone();
                self.warn(format_args!(
                    "{who}: the KHR_texture_transform of the {} texture of its material '{mname}' takes its texture coordinates out of the range of 32-bit floating point; sampled without the transform",
                    names.join(", ")
                ));
            }
        }

        if topology != Topology::Triangles {
            // No surface to take a normal or tangent frame from: the file's normals (repaired
            // where degenerate) and a fallback frame; unlit without normals (above).
            let bad = if normals.is_some() {
                vertices
                    .iter_mut()
                    .filter(|v| {
                        let n = glam::Vec3::from(v.normal);
                        !(n.length_squared() > 1e-12 && n.is_finite())
                    })
                    .map(|v| v.normal = [0.0, 0.0, 1.0])
                    .count()
            } else {
                for v in vertices.iter_mut() {
                    v.normal = [0.0, 0.0, 1.0];
                }
                0
            };
            for v in vertices.iter_mut() {
                v.normal = glam::Vec3::from(v.normal)
                    .normalize_or(glam::Vec3::Z)
                    .to_array();
                v.tangent = [0.0; 4];
            }
            tangents::repair_tangents(&mut vertices);
            if bad > 0 {
                self.warn(format_args!(
                    "{who}: {bad} normal(s) were zero-length or not finite; replaced by +Z"
                ));
            }
            return Ok(Some((
                Mesh {
                    name,
                    vertices,
                    indices,
                    material,
                    colors,
                    topology,
                },
                deform,
            )));
        }
        if normals.is_none() {
            // glTF 2.0 (3.7.2.1): "When normals are not specified, client implementations MUST
            // calculate flat normals and the provided tangents (if present) MUST be ignored."
            // A vertex is copied where the triangles sharing it disagree (tangents.rs).
            let no_targets = Vec::new();
            let targets = deform.as_ref().map_or(&no_targets, |d| &d.targets);
            let (flat, made) = tangents::flat_normals(&vertices, &mut indices, targets);
            vertices = flat;
            carry_along(&made.origin, &mut colors, deform.as_mut());
            if let Some(d) = deform.as_mut() {
                for (t, normals) in made.target_normals {
                    d.targets[t].normals = normals;
                }
            }
            if made.degenerate == indices.len() / 3 {
                self.warn(format_args!(
                    "{who} has no normals and none of its {} triangle(s) has an area, so it covers no pixel; check the mesh in your modelling tool",
                    made.degenerate
                ));
            }
        }
        let bad_normals = tangents::repair_normals(&mut vertices, &indices);

        let file_tangents = tangents.is_some() && normals.is_some();
        let bad_tangents = if file_tangents && !uv_transform.turns_or_mirrors() {
            tangents::repair_tangents(&mut vertices)
        } else if uvs.is_some() {
            let before = (deform.is_some() || !colors.is_empty()).then(|| indices.clone());
            // glTF: generated tangents follow the normal texture's coordinates: its set, through
            // its own transform (its map from the coordinates the vertices carry, which hold the
            // first TEXCOORD_0 slot's transform: materials.rs). A woven material's tangent is
            // its weave's thread direction, which follows the vertices' coordinates.
            // Without a normal texture, a clear coat's normal texture is the one to follow.
            let normal_map = self.scene.materials.get(material).and_then(|m| {
                let map = m.uv[m.tangent_slot()? as usize];
                (m.fabric.is_none() && map != SlotUv::IDENTITY).then_some(map)
            });
            let uv_of = move |v: &Vertex| normal_map.map_or(v.uv, |slot| slot.coordinates(v));
            if !tangents::mikktspace_tangents(&mut vertices, &mut indices, &uv_of) {
                tangents::arbitrary_tangents(&mut vertices);
            }
            // MikkTSpace splits vertices whose corners need different tangents: the copies get
            // their original's joints, morph deltas and colour.
            if let Some(before) = before {
                let mut origin: Vec<usize> = (0..vertices.len()).collect();
                for (now, was) in indices.iter().zip(&before) {
                    if now != was {
                        if let Some(o) = origin.get_mut(*now as usize) {
                            *o = *was as usize;
                        }
                    }
                }
                carry_along(&origin, &mut colors, deform.as_mut());
            }
            tangents::repair_tangents(&mut vertices)
        } else {
            tangents::arbitrary_tangents(&mut vertices);
            0
        };
        let repaired: Vec<String> = [(bad_normals, "normal"), (bad_tangents, "tangent")]
            .iter()
            .filter(|(n, _)| *n > 0)
            .map(|(n, what)| format!("{n} {what}(s)"))
            .collect();
        if !repaired.is_empty() {
            self.warn(format_args!(
                "{who}: {} were zero-length, degenerate or not finite; replaced by a fallback frame (check the mesh's normals and UVs in your modelling tool)",
                repaired.join(" and ")
            ));
        }

        Ok(Some((
            Mesh {
                name,
                vertices,
                indices,
                material,
                colors,
                topology: Topology::Triangles,
            },
            deform,
        )))
    }

    /// A primitive's COLOR_0 as linear RGBA per vertex (alpha 1 for VEC3), empty when it has
    /// none. glTF allows VEC3 or VEC4 of float, normalized unsigned byte or normalized unsigned
    /// short; anything else is ignored with a warning. Values are clamped to [0, 1] (a non-finite
    /// one becomes 1).
    pub(super) fn vertex_colors(
        &mut self,
        prim: &gltf::Primitive<'a>,
        who: &str,
        count: usize,
    ) -> Result<Vec<[f32; 4]>> {
        use gltf::accessor::DataType;
        let Some(acc) = prim.get(&Semantic::Colors(0)) else {
            return Ok(Vec::new());
        };
        let n = match acc.dimensions() {
            Dimensions::Vec3 => 3,
            Dimensions::Vec4 => 4,
            other => {
                self.warn(format_args!(
                    "{who}: COLOR_0 (accessor {}) is {other:?}; glTF allows VEC3 or VEC4, so the vertex colours are ignored: re-export the mesh",
                    acc.index()
                ));
                return Ok(Vec::new());
            }
        };
        let allowed = match acc.data_type() {
            DataType::F32 => true,
            DataType::U8 | DataType::U16 => acc.normalized(),
            _ => false,
        };
        if !allowed {
            self.warn(format_args!(
                "{who}: COLOR_0 (accessor {}) has component type {:?}{}; glTF allows float, normalized unsigned byte or normalized unsigned short, so the vertex colours are ignored: re-export the mesh",
                acc.index(),
                acc.data_type(),
                if acc.normalized() { ", normalized" } else { "" }
            ));
            return Ok(Vec::new());
        }
        let what = format!("{who}, attribute COLOR_0");
        let values = accessor::read_f32(
            &acc,
            acc.dimensions(),
            self.buffers,
            &Use {
                source: &self.label,
                what: &what,
            },
        )?;
        if values.len() / n != count {
            return Err(self.error(format_args!(
                "{who}: attribute COLOR_0 (accessor {}) has {} elements but POSITION has {count}; all attributes of a primitive must have the same count: re-export the mesh",
                acc.index(),
                values.len() / n
            )));
        }
        let mut out_of_range = 0usize;
        let colors = values
            .chunks_exact(n)
            .map(|c| {
                let mut rgba = [1.0f32; 4];
                for (k, v) in c.iter().enumerate() {
                    rgba[k] = if v.is_finite() {
                        v.clamp(0.0, 1.0)
                    } else {
                        1.0
                    };
                    if rgba[k] != *v {
                        out_of_range += 1;
                    }
                }
                rgba
            })
            .collect();
        if out_of_range > 0 {
            self.warn(format_args!(
                "{who}: COLOR_0 (accessor {}) has {out_of_range} component(s) outside [0, 1] or not finite; clamped (a non-finite one to 1)",
                acc.index()
            ));
        }
        Ok(colors)
    }

    /// A primitive's joint influences (JOINTS_0 / WEIGHTS_0) and morph targets, None when it has
    /// neither. `count` is its vertex count, which every one of these accessors must match.
    pub(super) fn primitive_deform(
        &mut self,
        prim: &gltf::Primitive<'a>,
        who: &str,
        count: usize,
    ) -> Result<Option<MeshDeform>> {
        let buffers = self.buffers;
        let label = self.label.clone();
        let read = |acc: gltf::Accessor, what: String, dims: Dimensions| -> Result<Vec<f32>> {
            let values = accessor::read_f32(
                &acc,
                dims,
                buffers,
                &Use {
                    source: &label,
                    what: &what,
                },
            )?;
            let n = match dims {
                Dimensions::Vec3 => 3,
                _ => 4,
            };
            if values.len() / n != count {
                return Err(Error::input(format!(
                    "{label}: {what} (accessor {}) has {} elements but POSITION has {count}; all attributes of a primitive must have the same count: re-export the mesh",
                    acc.index(),
                    values.len() / n
                )));
            }
            if values.iter().any(|v| !v.is_finite()) {
                return Err(Error::input(format!(
                    "{label}: {what} (accessor {}) holds a non-finite value; fix the mesh and re-export it",
                    acc.index()
                )));
            }
            Ok(values)
        };
        let mut deform = MeshDeform::default();
        match (
            prim.get(&Semantic::Joints(0)),
            prim.get(&Semantic::Weights(0)),
        ) {
            (Some(j), Some(w)) => {
                let check_joints = |this: &Self, j: &gltf::Accessor, set: u32| -> Result<()> {
                    if !matches!(
                        j.data_type(),
                        gltf::accessor::DataType::U8 | gltf::accessor::DataType::U16
                    ) || j.normalized()
                    {
                        return Err(this.error(format_args!(
                            "{who}: JOINTS_{set} (accessor {}) has component type {:?}{}; glTF requires unsigned byte or unsigned short joint indices: re-export the mesh",
                            j.index(),
                            j.data_type(),
                            if j.normalized() { ", normalized" } else { "" }
                        )));
                    }
                    Ok(())
                };
                check_joints(self, &j, 0)?;
                let joints = read(j, format!("{who}, attribute JOINTS_0"), Dimensions::Vec4)?;
                let weights = read(w, format!("{who}, attribute WEIGHTS_0"), Dimensions::Vec4)?;
                // More than four influences come in further sets (JOINTS_1 / WEIGHTS_1, ...):
                // weft's vertex holds four, so each vertex keeps its four strongest.
                let mut more = Vec::new();
                for set in 1u32.. {
                    let (Some(j), Some(w)) = (
                        prim.get(&Semantic::Joints(set)),
                        prim.get(&Semantic::Weights(set)),
                    ) else {
                        break;
                    };
                    check_joints(self, &j, set)?;
                    more.push((
                        read(
                            j,
                            format!("{who}, attribute JOINTS_{set}"),
                            Dimensions::Vec4,
                        )?,
                        read(
                            w,
                            format!("{who}, attribute WEIGHTS_{set}"),
                            Dimensions::Vec4,
                        )?,
                    ));
                }
                let mut unweighted = 0;
                // The largest weight left out (as a share of the vertex's total) and its vertex.
                let mut dropped = (0f32, 0usize);
                deform.skin = (0..count)
                    .map(|v| {
                        let mut j = [0u32; 4];
                        let mut w = [0f32; 4];
                        for k in 0..4 {
                            j[k] = joints[4 * v + k] as u32;
                            w[k] = weights[4 * v + k].max(0.0);
                        }
                        if !more.is_empty() {
                            let mut all: Vec<(u32, f32)> = j.into_iter().zip(w).collect();
                            for (js, ws) in &more {
                                all.extend(
                                    (0..4).map(|k| (js[4 * v + k] as u32, ws[4 * v + k].max(0.0))),
                                );
                            }
                            // A joint named twice is one influence; strongest first, the lower
                            // joint first between equals.
                            all.sort_by_key(|&(joint, _)| joint);
                            all.dedup_by(|b, a| {
                                let same = a.0 == b.0;
                                if same {
                                    a.1 += b.1;
                                }
                                same
                            });
                            all.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
                            let total: f32 = all.iter().map(|x| x.1).sum();
                            if let Some(&(_, cut)) = all.get(4) {
                                if total > 1e-6 && cut / total > dropped.0 {
                                    dropped = (cut / total, v);
                                }
                            }
                            all.resize(4.max(all.len()), (0, 0.0));
                            for k in 0..4 {
                                (j[k], w[k]) = all[k];
                            }
                        }
                        let sum: f32 = w.iter().sum();
                        let weights = if sum > 1e-6 {
                            // glTF asks for weights that sum to 1; exporters round (u8 weights
                            // especially), so they are normalised.
                            w.map(|x| x / sum)
                        } else {
                            unweighted += 1;
                            [1.0, 0.0, 0.0, 0.0]
                        };
                        VertexSkin { joints: j, weights }
                    })
                    .collect();
                if unweighted > 0 {
                    self.warn(format_args!(
                        "{who} has {unweighted} vertex/vertices whose WEIGHTS_0 are all zero; they follow their first joint"
                    ));
                }
                // Below 1 % of a vertex's weight a fifth influence moves it by under 1 % of its
                // joints' relative motion: not worth a message.
                if dropped.0 > 0.01 {
                    self.warn(format_args!(
                        "{who} has more than four joint influences per vertex ({} sets of JOINTS/WEIGHTS); weft keeps each vertex's four strongest, and the largest left out is {:.0} % of vertex {}'s weight, so the skin deforms slightly differently",
                        more.len() + 1,
                        dropped.0 * 100.0,
                        dropped.1
                    ));
                }
            }
            (None, None) => {}
            _ => {
                self.warn(format_args!(
                    "{who} has only one of JOINTS_0 and WEIGHTS_0; a skinned primitive needs both, so it is drawn unskinned"
                ));
            }
        }
        let targets: Vec<_> = prim.morph_targets().collect();
        if targets.len() > animation::MAX_MORPH_TARGETS {
            return Err(self.error(format_args!(
                "{who} has {} morph targets, more than weft's limit of {}; bake or drop some shape keys",
                targets.len(),
                animation::MAX_MORPH_TARGETS
            )));
        }
        let triples = |v: Vec<f32>| -> Vec<[f32; 3]> {
            v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
        };
        for (k, t) in targets.iter().enumerate() {
            let mut target = MorphTarget::default();
            if let Some(a) = t.positions() {
                target.positions = triples(read(
                    a,
                    format!("{who}, morph target {k} POSITION"),
                    Dimensions::Vec3,
                )?);
            }
            if let Some(a) = t.normals() {
                target.normals = triples(read(
                    a,
                    format!("{who}, morph target {k} NORMAL"),
                    Dimensions::Vec3,
                )?);
            }
            if let Some(a) = t.tangents() {
                target.tangents = triples(read(
                    a,
                    format!("{who}, morph target {k} TANGENT"),
                    Dimensions::Vec3,
                )?);
            }
            deform.targets.push(target);
        }
        Ok((!deform.skin.is_empty() || !deform.targets.is_empty()).then_some(deform))
    }
}

/// After a primitive's vertices were unwelded or split, vertex i is a copy of vertex
/// `origin[i]`: it gets that vertex's colour, joints and morph deltas.
fn carry_along(origin: &[usize], colors: &mut Vec<[f32; 4]>, deform: Option<&mut MeshDeform>) {
    if !colors.is_empty() {
        *colors = origin
            .iter()
            .map(|&o| colors.get(o).copied().unwrap_or([1.0; 4]))
            .collect();
    }
    if let Some(d) = deform {
        d.select(origin);
    }
}
