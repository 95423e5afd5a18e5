//! Lights (KHR_lights_punctual, with weft's shadow settings in `extras`) and cameras, before nodes place them.

use super::*;

impl<'a> Loader<'a> {
    // --- lights and cameras ---------------------------------------------------------------------

    pub(super) fn light_definitions(&mut self) -> Result<Vec<LightDef>> {
        let root = self.doc.as_json();
        let lights = root
            .extensions
            .as_ref()
            .and_then(|e| e.khr_lights_punctual.as_ref())
            .map_or(&[][..], |l| &l.lights[..]);
        let mut out = Vec::with_capacity(lights.len());
        for (i, l) in lights.iter().enumerate() {
            let name = l.name.clone().unwrap_or_else(|| format!("light {i}"));
            let who = format!("light '{name}' (KHR_lights_punctual light {i})");
            use json::extensions::scene::khr_lights_punctual::Type;
            let kind = match (&l.type_, &l.spot) {
                (Checked::Valid(Type::Directional), _) => LightKind::Directional,
                (Checked::Valid(Type::Point), _) => LightKind::Point,
                (Checked::Valid(Type::Spot), Some(spot)) => {
                    let (inner, outer) = (spot.inner_cone_angle, spot.outer_cone_angle);
                    let half_pi = std::f32::consts::FRAC_PI_2;
                    if !(inner.is_finite()
                        && outer.is_finite()
                        && 0.0 <= inner
                        && inner < outer
                        && outer <= half_pi)
                    {
                        return Err(self.error(format_args!(
                            "{who} has innerConeAngle {inner} and outerConeAngle {outer}; they must satisfy 0 <= inner < outer <= pi/2 (radians): fix the spot angles"
                        )));
                    }
                    LightKind::Spot {
                        inner_cone: inner,
                        outer_cone: outer,
                    }
                }
                _ => {
                    return Err(self.error(format_args!(
                        "{who} has no valid type and spot parameters; re-export the light"
                    )))
                }
            };
            if !(l.intensity.is_finite() && l.intensity >= 0.0) {
                return Err(self.error(format_args!(
                    "{who} has intensity {}; it must be a finite number >= 0",
                    l.intensity
                )));
            }
            if !l.color.iter().all(|c| c.is_finite() && *c >= 0.0) {
                return Err(self.error(format_args!(
                    "{who} has colour {:?}; components must be finite and >= 0",
                    l.color
                )));
            }
            let range = match (kind, l.range) {
                // The extension defines no range for directional lights.
                (LightKind::Directional, _) | (_, None) => None,
                (_, Some(r)) if r.is_finite() && r > 0.0 => Some(r),
                (_, Some(r)) => {
                    return Err(self.error(format_args!(
                        "{who} has range {r}; it must be > 0 (or left out for no cut-off)"
                    )))
                }
            };
            let shadow = self.light_shadow(&l.extras, kind, &who)?;
            out.push(LightDef {
                name,
                kind,
                color: l.color,
                intensity: l.intensity,
                range,
                shadow,
            });
        }
        Ok(out)
    }

    /// The shadow settings a light asks for with `extras.shadows` (docs/scene-format.md): `true`
    /// for the defaults, an object of optional `resolution`, `filter_radius` and `bias`, `false`
    /// or absent for none. Numbers out of range are clamped with a warning, unknown keys warned
    /// about; a value of the wrong type is an error. Point lights get a warning and no shadows.
    pub(super) fn light_shadow(
        &mut self,
        extras: &json::Extras,
        kind: LightKind,
        who: &str,
    ) -> Result<Option<Shadow>> {
        let Some(value) = extras_object(extras).and_then(|mut e| e.remove("shadows")) else {
            return Ok(None);
        };
        let example = r#"{"resolution": 2048, "filter_radius": 1.5, "bias": 1.0}"#;
        let fields = match value {
            serde_json::Value::Bool(false) => return Ok(None),
            serde_json::Value::Bool(true) => serde_json::Map::new(),
            serde_json::Value::Object(map) => map,
            other => {
                return Err(self.error(format_args!(
                    "{who} has extras.shadows = {}; it must be true (shadows with the default settings), false (no shadows) or an object such as {example} (each key optional): fix the light's extras",
                    short_json(&other)
                )))
            }
        };
        let mut shadow = Shadow::default();
        for (key, v) in &fields {
            let (lo, hi, what) = match key.as_str() {
                "resolution" => (
                    SHADOW_RESOLUTION_RANGE.0,
                    SHADOW_RESOLUTION_RANGE.1,
                    "the shadow map's size in texels",
                ),
                "filter_radius" => (
                    SHADOW_FILTER_RADIUS_RANGE.0,
                    SHADOW_FILTER_RADIUS_RANGE.1,
                    "the PCF filter radius in shadow-map texels",
                ),
                "bias" => (
                    SHADOW_BIAS_RANGE.0,
                    SHADOW_BIAS_RANGE.1,
                    "the depth bias in shadow-map texels",
                ),
                other => {
                    self.warn(format_args!(
                        "{who} has an unknown key '{other}' in extras.shadows (ignored); known keys: {SHADOW_KEYS}"
                    ));
                    continue;
                }
            };
            let x = match v.as_f64() {
                Some(x) if x.is_finite() && x.abs() <= f64::from(f32::MAX) => x,
                _ => {
                    let problem = if v.is_number() {
                        "a number too large for 32-bit floating point"
                    } else {
                        "not a number"
                    };
                    return Err(self.error(format_args!(
                        "{who} has extras.shadows.{key} = {}, {problem}; it must be a number ({what}, {lo} to {hi}): write one there, or remove the key for the default",
                        short_json(v)
                    )));
                }
            };
            let mut c = x.clamp(lo, hi);
            if key == "resolution" {
                c = c.round();
            }
            if c != x {
                let why = if (lo..=hi).contains(&x) {
                    "is not a whole number of texels; rounded to".to_string()
                } else {
                    format!("is outside [{lo}, {hi}]; clamped to")
                };
                self.warn(format_args!(
                    "{who} has extras.shadows.{key} = {}, which {why} {c}",
                    short_json(v)
                ));
            }
            match key.as_str() {
                "resolution" => shadow.resolution = c as u32,
                "filter_radius" => shadow.filter_radius = c as f32,
                _ => shadow.bias = c as f32,
            }
        }
        if kind == LightKind::Point {
            self.warn(format_args!(
                "{who} is a point light and asks for shadows (extras.shadows); weft casts shadows from directional and spot lights only, so this light is rendered without shadows"
            ));
            return Ok(None);
        }
        Ok(Some(shadow))
    }

    pub(super) fn camera_definitions(&mut self) -> Result<Vec<Option<CameraDef>>> {
        let root = self.doc.as_json();
        let mut out = Vec::with_capacity(root.cameras.len());
        for (i, c) in root.cameras.iter().enumerate() {
            let name = c.name.clone().unwrap_or_else(|| format!("camera {i}"));
            let who = format!("camera '{name}' (camera {i})");
            let p = match (&c.type_, &c.perspective) {
                (Checked::Valid(json::camera::Type::Perspective), Some(p)) => p,
                (Checked::Valid(json::camera::Type::Orthographic), _) => {
                    let Some(o) = c.orthographic.as_ref() else {
                        return Err(self.error(format_args!(
                            "{who} has type orthographic but no \"orthographic\" object; add one with xmag, ymag, znear and zfar"
                        )));
                    };
                    if !(o.xmag.is_finite() && o.xmag != 0.0 && o.ymag.is_finite() && o.ymag != 0.0) {
                        return Err(self.error(format_args!(
                            "{who} has xmag {} and ymag {}; both must be finite and not zero (half the width and height of the view, in metres): fix the camera",
                            o.xmag, o.ymag
                        )));
                    }
                    if o.xmag < 0.0 || o.ymag < 0.0 {
                        self.warn(format_args!(
                            "{who} has a negative xmag or ymag ({}, {}); glTF asks for positive ones, so their magnitudes are used",
                            o.xmag, o.ymag
                        ));
                    }
                    if !(o.znear.is_finite() && o.znear >= 0.0 && o.zfar.is_finite() && o.zfar > o.znear) {
                        return Err(self.error(format_args!(
                            "{who} has znear {} and zfar {}; an orthographic camera needs 0 <= znear < zfar, both finite: fix the camera",
                            o.znear, o.zfar
                        )));
                    }
                    out.push(Some(CameraDef {
                        name,
                        orthographic: Some([o.xmag.abs(), o.ymag.abs()]),
                        yfov: 45f32.to_radians(),
                        znear: o.znear,
                        zfar: Some(o.zfar),
                        aspect_ratio: Some(o.xmag.abs() / o.ymag.abs()),
                    }));
                    continue;
                }
                _ => {
                    return Err(self.error(format_args!(
                        "{who} has type perspective but no \"perspective\" object; add one with yfov and znear"
                    )))
                }
            };
            if !(p.yfov.is_finite() && p.yfov > 0.0 && p.yfov < std::f32::consts::PI) {
                return Err(self.error(format_args!(
                    "{who} has yfov {} rad; the vertical field of view must be between 0 and pi radians (exclusive): set perspective.yfov, e.g. 0.7 for 40 degrees",
                    p.yfov
                )));
            }
            if !(p.znear.is_finite() && p.znear > 0.0) {
                return Err(self.error(format_args!(
                    "{who} has znear {}; the near plane distance must be > 0: set perspective.znear, e.g. 0.05",
                    p.znear
                )));
            }
            if let Some(zfar) = p.zfar {
                if !(zfar.is_finite() && zfar > p.znear) {
                    return Err(self.error(format_args!(
                        "{who} has zfar {zfar} with znear {}; zfar must be greater than znear (or left out for an infinite far plane)",
                        p.znear
                    )));
                }
            }
            if let Some(a) = p.aspect_ratio {
                if !(a.is_finite() && a > 0.0) {
                    return Err(self.error(format_args!(
                        "{who} has aspectRatio {a}; it must be > 0 (or left out)"
                    )));
                }
            }
            out.push(Some(CameraDef {
                name,
                orthographic: None,
                yfov: p.yfov,
                znear: p.znear,
                zfar: p.zfar,
                aspect_ratio: p.aspect_ratio,
            }));
        }
        Ok(out)
    }
}
