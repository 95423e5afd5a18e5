//! What a person looks at: the images of every case under `target/regression/` and one index page
//! (`index.html`) with every case's figures and its images side by side.

use std::fmt::Write as _;
use std::path::Path;

use super::cases::Case;
use super::metrics::{Figures, Tolerance};

/// One comparison shown on the page: its figures against its tolerance, and its three images.
pub struct Shown {
    pub title: &'static str,
    pub figures: Figures,
    pub tolerance: Tolerance,
    pub violations: Vec<String>,
    /// File names (in the report folder) of the reference, the test image and the FLIP map.
    pub images: [String; 3],
    /// Captions of the three images.
    pub captions: [&'static str; 3],
}

/// Everything about one case.
pub struct Row {
    pub case: Case,
    pub render_ms: f64,
    /// Golden missing, blessed, or the reason nothing could be compared.
    pub note: Option<String>,
    pub shown: Vec<Shown>,
}

impl Row {
    pub fn passed(&self) -> bool {
        self.shown.iter().all(|s| s.violations.is_empty())
            && self.note.as_deref().is_none_or(|n| !n.starts_with("FAIL"))
    }
}

pub fn write_png(path: &Path, width: u32, height: u32, rgba_or_rgb: &[u8]) {
    let color = if rgba_or_rgb.len() == (width * height * 4) as usize {
        image::ExtendedColorType::Rgba8
    } else {
        image::ExtendedColorType::Rgb8
    };
    image::save_buffer(path, rgba_or_rgb, width, height, color)
        .unwrap_or_else(|e| panic!("cannot write {}: {e}", path.display()));
}

/// Text made safe for the page, in element content and in quoted attributes alike.
fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&#39;")
}

/// Writes `index.html` into `dir`.
pub fn write_index(dir: &Path, header: &str, rows: &[Row]) {
    let mut h = String::new();
    let failed = rows.iter().filter(|r| !r.passed()).count();
    let _ = write!(
        h,
        r#"<!doctype html><meta charset="utf-8"><title>weft image regression</title>
<style>
body {{ font: 14px/1.4 system-ui, sans-serif; margin: 1.5em; background: #fafafa; color: #222 }}
section {{ background: #fff; border: 1px solid #ddd; border-left: 6px solid #3a3; padding: 0.6em 1em; margin: 1em 0 }}
section.fail {{ border-left-color: #c22 }}
h2 {{ margin: 0.2em 0; font-size: 1.15em }}
.fig {{ display: inline-block; margin: 0 0.8em 0.4em 0; vertical-align: top }}
.fig img {{ width: 384px; image-rendering: pixelated; border: 1px solid #ccc; display: block }}
.fail-text {{ color: #c22; font-weight: bold }}
code {{ background: #eee; padding: 0 0.2em }}
table {{ border-collapse: collapse }} td {{ padding: 0 0.8em 0 0 }}
</style>
<h1>weft image regression</h1>
<p>{}</p>
<p><b>{} of {} cases failed.</b> Each comparison shows the reference, the image under test and
their FLIP error map (magma: black = no visible difference, yellow-white = obvious). Bless new
goldens with <code>tools/bless</code> after looking at them (docs/regression.md).</p>
"#,
        escape(header),
        failed,
        rows.len()
    );
    for row in rows {
        let c = &row.case;
        let _ = write!(
            h,
            "<section class=\"{}\" id=\"{}\"><h2>{} — {}</h2><p>{}<br><small><code>{}</code>, camera {}, debug view {}, accuracy {}, weave {}, rendered in {:.0} ms</small></p>",
            if row.passed() { "pass" } else { "fail" },
            escape(c.name),
            escape(c.name),
            if row.passed() { "pass" } else { "<span class=\"fail-text\">FAIL</span>" },
            escape(c.shows),
            escape(c.scene),
            c.camera.map(|i| i.to_string()).unwrap_or_else(|| "first".into()),
            c.debug_view.name(),
            c.accuracy.name(),
            c.weave_precision.name(),
            row.render_ms
        );
        if let Some(note) = &row.note {
            let _ = write!(
                h,
                "<p class=\"{}\">{}</p>",
                if note.starts_with("FAIL") {
                    "fail-text"
                } else {
                    ""
                },
                escape(note)
            );
        }
        for s in &row.shown {
            let _ = write!(
                h,
                "<h3>{}</h3><table><tr><td>figures</td><td>{}</td></tr><tr><td>bound</td><td>{}</td></tr>",
                escape(s.title),
                escape(&s.figures.summary(&s.tolerance)),
                escape(&s.tolerance.describe())
            );
            if !s.violations.is_empty() {
                let _ = write!(
                    h,
                    "<tr><td>fails</td><td class=\"fail-text\">{}</td></tr>",
                    escape(&s.violations.join("; "))
                );
            }
            h.push_str("</table><div>");
            for (img, cap) in s.images.iter().zip(s.captions) {
                let (img, cap) = (escape(img), escape(cap));
                let _ = write!(h, "<div class=\"fig\"><a href=\"{img}\"><img src=\"{img}\" alt=\"{cap}\"></a>{cap}</div>");
            }
            h.push_str("</div>");
        }
        h.push_str("</section>\n");
    }
    let path = dir.join("index.html");
    weft::render::write_file(&path, h.as_bytes())
        .unwrap_or_else(|e| panic!("cannot write {}: {e}", path.display()));
}

#[test]
fn the_page_escapes_quotes_and_the_header() {
    assert_eq!(
        escape(r#"<a href="x">'&'</a>"#),
        "&lt;a href=&quot;x&quot;&gt;&#39;&amp;&#39;&lt;/a&gt;"
    );
    // The header holds driver strings: a hostile one stays text.
    let dir = crate::common::temp_dir("report");
    write_index(&dir, r#"llvmpipe "<script>alert(1)</script>" & co"#, &[]);
    let page = std::fs::read_to_string(dir.join("index.html")).unwrap();
    assert!(!page.contains("<script>"), "{page}");
    assert!(
        page.contains("llvmpipe &quot;&lt;script&gt;alert(1)&lt;/script&gt;&quot; &amp; co"),
        "{page}"
    );
    let _ = std::fs::remove_dir_all(dir);
}
