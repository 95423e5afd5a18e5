//! Named fabrics for `weft fabric --preset` and `weft render --fabric MATERIAL=PRESET`: the
//! parameters of `WEFT_materials_fabric` for a few common cloths, with the thread pitch in world
//! units (the command converts it to texture units with the mesh's UV density).
//!
//! Where the numbers come from (the same text is in `docs/fabric-on-assets.md`):
//!
//! - **Pattern**: the textile definition of each weave (plain; 3/1 warp-faced twill for denim;
//!   5-harness warp-faced satin), as `docs/fabric-model.md` §2 defines the patterns.
//! - **Pitch** (centre-to-centre distance of neighbouring threads, one cell = `s_p/2`): from
//!   common thread counts, rounded. Quilting/poplin cotton is sold at about 68 × 68 threads per
//!   inch (0.37 mm); denim has about 60–70 warp ends and 40–50 weft picks per inch (0.4–0.6 mm;
//!   the model has one pitch for both, 0.5 mm); polyester taffeta is sold as "190T" to "210T"
//!   (warp + weft threads per inch, so about 100 each way: 0.25 mm); silk satin (charmeuse) is
//!   far denser, of the order of 100+ ends per cm (0.1 mm is used). These are typical retail
//!   figures, not measurements of a particular cloth.
//! - **Rs**: Schlick's normal-incidence reflectance `((n − 1)/(n + 1))²` of the fibre polymer:
//!   cellulose (cotton) n ≈ 1.53–1.58 → 0.045; silk fibroin n ≈ 1.54–1.59 → 0.047; PET (polyester)
//!   n ≈ 1.53 across / 1.72 along the fibre, mean ≈ 1.60 → 0.053. The paper gives no values.
//! - **Exponents, gap, thread shadow, colours**: chosen by eye in weft's renders; the paper prints
//!   no parameter table (its OCR has none either), and `docs/fabric-model.md`'s example (200/10,
//!   the project default) is the starting point. Spun staple yarns (cotton, denim) are hairy, so
//!   their lobes are wide (low exponents); continuous filaments (silk, polyester) are smooth and
//!   narrow (high exponents); satin floats are long and flat, hence the highest `e_along`. Gaps
//!   are a fraction of the pitch: tight weaves (denim, satin) small, poplin larger.
//! - **Thread transmittance** (used only for a single sheet, `--sheet`): by eye, ordered by
//!   yarn: a fine continuous filament (silk, polyester) passes more of its diffuse light than a
//!   spun cotton thread, and a thick indigo-dyed denim yarn little. Not measured.
//! - Denim: warp indigo, weft undyed ecru (the defining feature of denim); the other colours are
//!   neutral mid-tones meant to be overridden (`--rd`, or `--rd base` for the material's own
//!   base colour).

use super::{FabricParams, WeavePattern};

/// A named fabric.
#[derive(Clone, Debug)]
pub struct Preset {
    /// What `--preset` takes.
    pub name: &'static str,
    /// One line for `--list-presets`.
    pub summary: &'static str,
    /// Pattern name (`WeavePattern::by_name`).
    pub pattern: &'static str,
    /// Thread pitch in metres (centre to centre; one cell of the pattern).
    pub pitch_m: f64,
    /// The gap between neighbouring threads as a fraction of the pitch, [0, 1]: the extension's
    /// `gap = gap_fraction · repeat / 2`.
    pub gap_fraction: f64,
    pub e_along: f32,
    pub e_across: f32,
    /// Linear RGB.
    pub rd_warp: [f32; 3],
    pub rd_weft: [f32; 3],
    pub rs: f32,
    pub shadow_strength: f32,
    pub shadow_width: f32,
    /// The threads' diffuse transmittance when the cloth is a single sheet (`weft fabric
    /// --sheet`): the share of a thread's diffuse light that leaves through its other side.
    pub thread_transmittance: f32,
    /// Where the numbers come from, for `--list-presets`.
    pub sources: &'static str,
}

/// The presets, in the order `--list-presets` prints them.
pub const PRESETS: &[Preset] = &[
    Preset {
        name: "cotton-plain",
        summary: "cotton poplin / quilting cotton, plain weave, matte",
        pattern: "plain",
        pitch_m: 0.37e-3,
        gap_fraction: 0.12,
        e_along: 60.0,
        e_across: 4.0,
        rd_warp: [0.62, 0.60, 0.56],
        rd_weft: [0.62, 0.60, 0.56],
        rs: 0.045,
        shadow_strength: 0.5,
        shadow_width: 0.25,
        thread_transmittance: 0.3,
        sources: "pitch: ~68x68 threads/inch retail quilting cotton; rs: cellulose n~1.55; \
                  exponents, gap, colour: by eye",
    },
    Preset {
        name: "denim-twill",
        summary: "denim, 3/1 warp-faced twill, indigo warp over ecru weft",
        pattern: "twill",
        pitch_m: 0.5e-3,
        gap_fraction: 0.06,
        e_along: 100.0,
        e_across: 6.0,
        rd_warp: [0.02, 0.05, 0.18],
        rd_weft: [0.45, 0.42, 0.36],
        rs: 0.045,
        shadow_strength: 0.6,
        shadow_width: 0.3,
        thread_transmittance: 0.08,
        sources:
            "pattern: denim is a 3/1 warp-faced twill; pitch: ~60-70 ends x 40-50 picks/inch; \
                  rs: cellulose n~1.55; exponents, gap, shadow, colours: by eye",
    },
    Preset {
        name: "silk-satin",
        summary: "silk satin (charmeuse), 5-harness satin, glossy",
        pattern: "satin",
        pitch_m: 0.1e-3,
        gap_fraction: 0.03,
        e_along: 800.0,
        e_across: 30.0,
        rd_warp: [0.55, 0.50, 0.45],
        rd_weft: [0.55, 0.50, 0.45],
        rs: 0.047,
        shadow_strength: 0.4,
        shadow_width: 0.2,
        thread_transmittance: 0.45,
        sources: "pattern: satin weave; pitch: order of 100+ ends/cm for silk satin; \
                  rs: silk fibroin n~1.56; exponents (smooth filament), gap, colour: by eye",
    },
    Preset {
        name: "polyester-plain",
        summary: "polyester taffeta (190T-210T), plain weave of filament yarn, semi-gloss",
        pattern: "plain",
        pitch_m: 0.25e-3,
        gap_fraction: 0.05,
        e_along: 400.0,
        e_across: 20.0,
        rd_warp: [0.45, 0.45, 0.47],
        rd_weft: [0.45, 0.45, 0.47],
        rs: 0.053,
        shadow_strength: 0.45,
        shadow_width: 0.25,
        thread_transmittance: 0.4,
        sources: "pitch: 190T-210T taffeta = warp+weft threads/inch; rs: PET n~1.60 (mean of \
                  1.53 and 1.72); exponents, gap, colour: by eye",
    },
];

/// The preset called `name` (exact, case-insensitive).
pub fn by_name(name: &str) -> Option<&'static Preset> {
    PRESETS.iter().find(|p| p.name.eq_ignore_ascii_case(name))
}

/// The names, comma-separated, for messages.
pub fn names() -> String {
    PRESETS
        .iter()
        .map(|p| p.name)
        .collect::<Vec<_>>()
        .join(", ")
}

impl Preset {
    /// The extension's parameters with the repeat `s_p` (texture units) the pitch became.
    pub fn params(&self, repeat: f32) -> FabricParams {
        FabricParams {
            pattern: WeavePattern::by_name(self.pattern)
                .expect("presets name known patterns (tested)"),
            repeat,
            gap: (self.gap_fraction * repeat as f64 / 2.0) as f32,
            e_along: self.e_along,
            e_across: self.e_across,
            rd_warp: self.rd_warp,
            rd_weft: self.rd_weft,
            rs: self.rs,
            shadow_strength: self.shadow_strength,
            shadow_width: self.shadow_width,
            coupled_diffuse: false,
            thread_texture: crate::fabric::ThreadTexture::BaseColor,
            warp_colours: Vec::new(),
            weft_colours: Vec::new(),
            transmission: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_are_in_range_and_findable() {
        for p in PRESETS {
            assert!(WeavePattern::by_name(p.pattern).is_some(), "{}", p.name);
            assert!(by_name(&p.name.to_uppercase()).is_some());
            let params = p.params(0.01);
            // Nothing would be clamped by the loader: sanitising changes nothing.
            assert_eq!(params.sanitized(), params, "{}", p.name);
            assert!(p.pitch_m > 1e-5 && p.pitch_m < 1e-2, "{}", p.name);
            assert!((0.0..=1.0).contains(&p.gap_fraction));
        }
        assert!(by_name("tweed").is_none());
    }
}
