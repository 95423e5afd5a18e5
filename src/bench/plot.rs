//! The bench plot: error (FLIP mean) against time (G-buffer + lighting ms), log-log, one curve per
//! view through the levels at the default precision, the other precisions as other markers.
//!
//! Drawn here on an RGB canvas: antialiased lines and markers from distances, text from an
//! embedded 5x7 bitmap font, so that no font file and no system library is needed.

use std::collections::BTreeMap;

use super::{BenchReport, View};
use crate::render::{Accuracy, WeavePrecision};

type Rgb = [f32; 3];

const WHITE: Rgb = [1.0, 1.0, 1.0];
pub(crate) const BLACK: Rgb = [0.1, 0.1, 0.12];
const GRID: Rgb = [0.88, 0.88, 0.9];
pub(crate) const MUTED: Rgb = [0.35, 0.35, 0.4];

/// One colour per view (the first four of a common categorical palette).
fn view_color(view: View) -> Rgb {
    let c: [u8; 3] = match view {
        View::CloseUp => [31, 119, 180],
        View::Mid => [255, 127, 14],
        View::Far => [44, 160, 44],
        View::Grazing => [214, 39, 40],
        View::Cells10 => [148, 103, 189],
        View::Cells1 => [140, 86, 75],
        View::Cells1Square => [227, 119, 194],
        View::Cells15Square => [127, 127, 127],
        View::CellsGrazing => [188, 189, 34],
    };
    [
        c[0] as f32 / 255.0,
        c[1] as f32 / 255.0,
        c[2] as f32 / 255.0,
    ]
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Shape {
    Circle,
    Square,
    Diamond,
    Triangle,
}

fn precision_shape(p: WeavePrecision) -> Shape {
    match p {
        WeavePrecision::Rgba16f => Shape::Circle,
        WeavePrecision::Rgba8 => Shape::Square,
        WeavePrecision::Analytic => Shape::Diamond,
        WeavePrecision::Sat => Shape::Triangle,
    }
}

/// Short label of a level on the plot.
fn level_label(level: Accuracy) -> String {
    match level {
        Accuracy::Nearest => "N".into(),
        Accuracy::FilteredParams => "FP".into(),
        Accuracy::Mixture => "MIX".into(),
        Accuracy::Supersampled(n) => format!("SS{n}"),
    }
}

/// An RGB canvas with coverage-blended drawing.
pub struct Canvas {
    pub width: u32,
    pub height: u32,
    px: Vec<Rgb>,
}

impl Canvas {
    pub fn new(width: u32, height: u32, background: Rgb) -> Canvas {
        Canvas {
            width,
            height,
            px: vec![background; (width * height) as usize],
        }
    }

    fn blend(&mut self, x: i32, y: i32, c: Rgb, a: f32) {
        if x < 0 || y < 0 || x >= self.width as i32 || y >= self.height as i32 || a <= 0.0 {
            return;
        }
        let a = a.min(1.0);
        let p = &mut self.px[(y as u32 * self.width + x as u32) as usize];
        for i in 0..3 {
            p[i] = p[i] * (1.0 - a) + c[i] * a;
        }
    }

    /// Copies an RGBA8 image (display-referred bytes, alpha ignored) with its top-left corner at
    /// (x, y); what falls outside the canvas is cut off.
    pub fn image(&mut self, x: i32, y: i32, width: u32, height: u32, rgba: &[u8]) {
        for row in 0..height as i32 {
            for col in 0..width as i32 {
                let i = ((row as u32 * width + col as u32) * 4) as usize;
                let Some(p) = rgba.get(i..i + 3) else { return };
                let c = [
                    p[0] as f32 / 255.0,
                    p[1] as f32 / 255.0,
                    p[2] as f32 / 255.0,
                ];
                self.blend(x + col, y + row, c, 1.0);
            }
        }
    }

    pub fn fill_rect(&mut self, x0: i32, y0: i32, x1: i32, y1: i32, c: Rgb) {
        for y in y0..y1 {
            for x in x0..x1 {
                self.blend(x, y, c, 1.0);
            }
        }
    }

    /// Fills every pixel whose centre is within the shape's `coverage` (a signed distance: < 0
    /// inside), antialiased over one pixel.
    fn fill_sdf(&mut self, bounds: (f32, f32, f32, f32), c: Rgb, sdf: impl Fn(f32, f32) -> f32) {
        let (x0, y0, x1, y1) = bounds;
        for y in (y0.floor() as i32 - 1)..=(y1.ceil() as i32 + 1) {
            for x in (x0.floor() as i32 - 1)..=(x1.ceil() as i32 + 1) {
                let d = sdf(x as f32 + 0.5, y as f32 + 0.5);
                self.blend(x, y, c, (0.5 - d).clamp(0.0, 1.0));
            }
        }
    }

    /// A straight line of the given width with round ends.
    pub fn line(&mut self, a: (f32, f32), b: (f32, f32), width: f32, c: Rgb) {
        let r = width * 0.5;
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let len2 = (dx * dx + dy * dy).max(1e-12);
        let bounds = (
            a.0.min(b.0) - r,
            a.1.min(b.1) - r,
            a.0.max(b.0) + r,
            a.1.max(b.1) + r,
        );
        self.fill_sdf(bounds, c, |x, y| {
            let t = (((x - a.0) * dx + (y - a.1) * dy) / len2).clamp(0.0, 1.0);
            let (px, py) = (a.0 + t * dx - x, a.1 + t * dy - y);
            (px * px + py * py).sqrt() - r
        });
    }

    /// A dashed line (dash and gap in pixels).
    pub fn dashed(
        &mut self,
        a: (f32, f32),
        b: (f32, f32),
        width: f32,
        dash: f32,
        gap: f32,
        c: Rgb,
    ) {
        let len = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
        let mut s = 0.0;
        while s < len {
            let e = (s + dash).min(len);
            let p = |t: f32| (a.0 + (b.0 - a.0) * t / len, a.1 + (b.1 - a.1) * t / len);
            self.line(p(s), p(e), width, c);
            s += dash + gap;
        }
    }

    fn marker(&mut self, shape: Shape, cx: f32, cy: f32, r: f32, fill: Rgb, outline: Rgb) {
        let sdf = |shape: Shape, r: f32| {
            move |x: f32, y: f32| {
                let (dx, dy) = ((x - cx).abs(), (y - cy).abs());
                match shape {
                    Shape::Circle => (dx * dx + dy * dy).sqrt() - r,
                    Shape::Square => dx.max(dy) - r * 0.85,
                    Shape::Diamond => (dx + dy) * std::f32::consts::FRAC_1_SQRT_2 - r * 0.85,
                    // Pointing up: the bottom edge and the two slanted sides.
                    Shape::Triangle => {
                        let y = y - cy;
                        (y - r * 0.7).max(dx * 0.866 - y * 0.5 - r * 0.5)
                    }
                }
            }
        };
        let b = (cx - r - 2.0, cy - r - 2.0, cx + r + 2.0, cy + r + 2.0);
        self.fill_sdf(b, outline, sdf(shape, r + 1.2));
        self.fill_sdf(b, fill, sdf(shape, r));
    }

    /// Draws `text` with its top-left corner at (x, y), each font pixel `scale` pixels wide;
    /// returns the width drawn.
    pub fn text(&mut self, x: i32, y: i32, text: &str, scale: i32, c: Rgb) -> i32 {
        let mut cx = x;
        for g in glyphs(text) {
            for (row, bits) in g.iter().enumerate() {
                for col in 0..5 {
                    if bits & (0x10 >> col) != 0 {
                        let (px, py) = (cx + col * scale, y + row as i32 * scale);
                        self.fill_rect(px, py, px + scale, py + scale, c);
                    }
                }
            }
            cx += 6 * scale;
        }
        cx - x
    }

    /// Text rotated a quarter turn counter-clockwise (reading bottom to top), its baseline's start
    /// at (x, y).
    pub fn text_up(&mut self, x: i32, y: i32, text: &str, scale: i32, c: Rgb) {
        let mut cy = y;
        for g in glyphs(text) {
            for (row, bits) in g.iter().enumerate() {
                for col in 0..5 {
                    if bits & (0x10 >> col) != 0 {
                        let (px, py) = (x + row as i32 * scale, cy - (col + 1) * scale);
                        self.fill_rect(px, py, px + scale, py + scale, c);
                    }
                }
            }
            cy -= 6 * scale;
        }
    }

    pub fn to_rgba8(&self) -> Vec<u8> {
        let q = |v: f32| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
        self.px
            .iter()
            .flat_map(|p| [q(p[0]), q(p[1]), q(p[2]), 255])
            .collect()
    }
}

pub fn text_width(text: &str, scale: i32) -> i32 {
    (text.chars().count() as i32 * 6 - 1).max(0) * scale
}

/// The glyphs of a text: `x` between digits (640x360) is the small multiplication x, every other
/// letter a capital.
fn glyphs(text: &str) -> Vec<[u8; 7]> {
    let chars: Vec<char> = text.chars().collect();
    (0..chars.len())
        .map(|i| {
            let digit = |j: Option<usize>| {
                j.and_then(|j| chars.get(j))
                    .is_some_and(|c| c.is_ascii_digit())
            };
            if chars[i] == 'x' && digit(i.checked_sub(1)) && digit(Some(i + 1)) {
                glyph('x')
            } else {
                glyph(chars[i].to_ascii_uppercase())
            }
        })
        .collect()
}

/// A 5x7 bitmap font: rows top to bottom, bit 4 is the leftmost column. Lower-case letters are
/// drawn as capitals, except `x` (for sizes like 640x360); unknown characters as `?`.
fn glyph(c: char) -> [u8; 7] {
    match c {
        '0' => [0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E],
        '1' => [0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E],
        '2' => [0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F],
        '3' => [0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E],
        '4' => [0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02],
        '5' => [0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E],
        '6' => [0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E],
        '7' => [0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08],
        '8' => [0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E],
        '9' => [0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C],
        'A' => [0x0E, 0x11, 0x11, 0x11, 0x1F, 0x11, 0x11],
        'B' => [0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E],
        'C' => [0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E],
        'D' => [0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C],
        'E' => [0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F],
        'F' => [0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10],
        'G' => [0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F],
        'H' => [0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11],
        'I' => [0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E],
        'J' => [0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C],
        'K' => [0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11],
        'L' => [0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F],
        'M' => [0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11],
        'N' => [0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11],
        'O' => [0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E],
        'P' => [0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10],
        'Q' => [0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D],
        'R' => [0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11],
        'S' => [0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E],
        'T' => [0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04],
        'U' => [0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E],
        'V' => [0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04],
        'W' => [0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A],
        'X' => [0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11],
        'Y' => [0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04],
        'Z' => [0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F],
        'x' => [0x00, 0x00, 0x11, 0x0A, 0x04, 0x0A, 0x11],
        ' ' => [0x00; 7],
        '.' => [0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C],
        ',' => [0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08],
        ':' => [0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00],
        ';' => [0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x04, 0x08],
        '-' => [0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00],
        '+' => [0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00],
        '=' => [0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00],
        '/' => [0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00],
        '(' => [0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02],
        ')' => [0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08],
        '[' => [0x0E, 0x08, 0x08, 0x08, 0x08, 0x08, 0x0E],
        ']' => [0x0E, 0x02, 0x02, 0x02, 0x02, 0x02, 0x0E],
        '%' => [0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03],
        '_' => [0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F],
        '<' => [0x02, 0x04, 0x08, 0x10, 0x08, 0x04, 0x02],
        '>' => [0x08, 0x04, 0x02, 0x01, 0x02, 0x04, 0x08],
        '*' => [0x00, 0x04, 0x15, 0x0E, 0x15, 0x04, 0x00],
        '#' => [0x0A, 0x0A, 0x1F, 0x0A, 0x1F, 0x0A, 0x0A],
        '\'' => [0x0C, 0x04, 0x08, 0x00, 0x00, 0x00, 0x00],
        '^' => [0x04, 0x0A, 0x11, 0x00, 0x00, 0x00, 0x00],
        '?' => [0x0E, 0x11, 0x01, 0x02, 0x04, 0x00, 0x04],
        c if c.is_ascii_lowercase() && c != 'x' => glyph(c.to_ascii_uppercase()),
        _ => glyph('?'),
    }
}

/// A log-10 axis mapped onto pixels [p0, p1].
#[derive(Clone, Copy)]
pub(crate) struct LogAxis {
    lo: f64,
    hi: f64,
    p0: f32,
    p1: f32,
}

impl LogAxis {
    /// Fits [min, max] with some margin, widened to at least one decade.
    pub(crate) fn fit(min: f64, max: f64, p0: f32, p1: f32) -> LogAxis {
        let (mut lo, mut hi) = (min.log10() - 0.08, max.log10() + 0.08);
        if hi - lo < 1.0 {
            let mid = 0.5 * (lo + hi);
            lo = mid - 0.5;
            hi = mid + 0.5;
        }
        LogAxis { lo, hi, p0, p1 }
    }

    pub(crate) fn map(&self, v: f64) -> f32 {
        let t = (v.max(1e-30).log10() - self.lo) / (self.hi - self.lo);
        self.p0 + (self.p1 - self.p0) * t as f32
    }

    /// Tick values: 1, 2, 5 x 10^k inside the range (only decades when the range is wide);
    /// (value, is_decade).
    pub(crate) fn ticks(&self) -> Vec<(f64, bool)> {
        let steps: &[f64] = if self.hi - self.lo > 3.5 {
            &[1.0]
        } else {
            &[1.0, 2.0, 5.0]
        };
        let mut out = Vec::new();
        for k in (self.lo.floor() as i32)..=(self.hi.ceil() as i32) {
            for &s in steps {
                let v = s * 10f64.powi(k);
                let l = v.log10();
                if l >= self.lo && l <= self.hi {
                    out.push((v, s == 1.0));
                }
            }
        }
        out
    }
}

fn tick_label(v: f64) -> String {
    if v >= 1.0 {
        format!("{v:.0}")
    } else {
        let digits = (-v.log10()).ceil().max(1.0) as usize;
        format!("{v:.digits$}")
    }
}

/// The horizontal grid lines, ticks and tick labels of a log y axis between x = left and right.
pub(crate) fn log_y_grid(c: &mut Canvas, y: &LogAxis, left: f32, right: f32) {
    for (v, decade) in y.ticks() {
        let py = y.map(v);
        c.line(
            (left, py),
            (right, py),
            if decade { 1.2 } else { 0.8 },
            GRID,
        );
        c.line((left - 6.0, py), (left, py), 1.0, BLACK);
        let label = tick_label(v);
        c.text(
            left as i32 - 10 - text_width(&label, 2),
            py as i32 - 7,
            &label,
            2,
            BLACK,
        );
    }
}

/// The grid, ticks and tick labels of a log-log plot, and its frame, in the box
/// (left, right, top, bottom).
pub(crate) fn log_frame(
    c: &mut Canvas,
    x: &LogAxis,
    y: &LogAxis,
    (left, right, top, bottom): (f32, f32, f32, f32),
) {
    for (v, decade) in x.ticks() {
        let px = x.map(v);
        c.line(
            (px, top),
            (px, bottom),
            if decade { 1.2 } else { 0.8 },
            GRID,
        );
        c.line((px, bottom), (px, bottom + 6.0), 1.0, BLACK);
        let label = tick_label(v);
        c.text(
            px as i32 - text_width(&label, 2) / 2,
            bottom as i32 + 12,
            &label,
            2,
            BLACK,
        );
    }
    log_y_grid(c, y, left, right);
    c.line((left, top), (left, bottom), 1.5, BLACK);
    c.line((left, bottom), (right, bottom), 1.5, BLACK);
    c.line((left, top), (right, top), 1.0, MUTED);
    c.line((right, top), (right, bottom), 1.0, MUTED);
}

/// Draws the plot of a report; returns (width, height, RGBA8 pixels).
pub fn plot(report: &BenchReport) -> (u32, u32, Vec<u8>) {
    const W: u32 = 1440;
    const H: u32 = 900;
    let (left, right, top, bottom) = (130.0f32, 1150.0f32, 70.0f32, 810.0f32);
    let mut c = Canvas::new(W, H, WHITE);

    // Error can be 0 (a variant identical to the truth): floor it for the log axis.
    const FLOOR: f64 = 1e-4;
    let points: Vec<_> = report
        .accuracy
        .iter()
        .filter(|r| r.times.total_ms() > 0.0)
        .map(|r| (r, r.times.total_ms(), r.flip_mean.max(FLOOR)))
        .collect();
    let (w, h) = report.size;
    let title = format!(
        "WEFT BENCH: ERROR AGAINST TIME, {w}x{h}, {}",
        report.machine.device
    );
    c.text(left as i32, 22, &title, 2, BLACK);
    c.text(
        left as i32,
        46,
        "FLIP mean over the fabric vs the pixel-integrating ground truth (jittered point samples); time = G-buffer + lighting GPU ms, median of warm frames",
        1,
        MUTED,
    );
    if points.is_empty() {
        c.text(left as i32, 300, "no measurements", 3, BLACK);
        return (W, H, c.to_rgba8());
    }
    let tmin = points.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    let tmax = points.iter().map(|p| p.1).fold(0.0, f64::max);
    let emin = points.iter().map(|p| p.2).fold(f64::INFINITY, f64::min);
    let emax = points.iter().map(|p| p.2).fold(0.0, f64::max);
    let x = LogAxis::fit(tmin, tmax, left, right);
    let y = LogAxis::fit(emin, emax, bottom, top);

    log_frame(&mut c, &x, &y, (left, right, top, bottom));
    let xlabel = "G-BUFFER + LIGHTING TIME (MS, LOG SCALE)";
    c.text(
        ((left + right) as i32 - text_width(xlabel, 2)) / 2,
        bottom as i32 + 40,
        xlabel,
        2,
        BLACK,
    );
    c.text_up(
        20,
        ((top + bottom) as i32 + text_width("FLIP MEAN (LOG SCALE)", 2)) / 2,
        "FLIP MEAN (LOG SCALE)",
        2,
        BLACK,
    );

    if emin <= FLOOR {
        c.dashed(
            (left, y.map(FLOOR)),
            (right, y.map(FLOOR)),
            1.0,
            6.0,
            4.0,
            MUTED,
        );
    }

    let mut precisions: BTreeMap<&'static str, usize> = BTreeMap::new();
    for r in &report.accuracy {
        *precisions.entry(r.precision.name()).or_default() += 1;
    }
    let mut views: Vec<View> = Vec::new();
    let mut levels: Vec<Accuracy> = Vec::new();
    for r in &report.accuracy {
        if !views.contains(&r.view) {
            views.push(r.view);
        }
        if !levels.contains(&r.level) {
            levels.push(r.level);
        }
    }
    // Each view's curve runs through its levels in order, at the default precision (sat)
    // where the level was measured with it, else at the first precision it was measured with
    // (the supersampled levels: analytic). Those points carry the level labels.
    let on_curve = |r: &super::AccuracyRow| {
        let same: Vec<_> = report
            .accuracy
            .iter()
            .filter(|o| o.view == r.view && o.level == r.level)
            .collect();
        let pick = same
            .iter()
            .find(|o| o.precision == WeavePrecision::default())
            .or(same.first());
        pick.is_some_and(|o| o.precision == r.precision)
    };
    // Curves first, markers over them, labels last.
    for &view in &views {
        let color = view_color(view);
        let curve: Vec<(f32, f32)> = levels
            .iter()
            .filter_map(|&l| {
                points
                    .iter()
                    .find(|p| p.0.view == view && p.0.level == l && on_curve(p.0))
            })
            .map(|p| (x.map(p.1), y.map(p.2)))
            .collect();
        for seg in curve.windows(2) {
            c.line(seg[0], seg[1], 2.5, color);
        }
    }
    for p in &points {
        let (px, py) = (x.map(p.1), y.map(p.2));
        let r = if on_curve(p.0) { 5.5 } else { 4.5 };
        if p.0.pareto {
            c.marker(Shape::Circle, px, py, r + 5.0, BLACK, WHITE);
            c.marker(Shape::Circle, px, py, r + 3.5, WHITE, WHITE);
        }
        c.marker(
            precision_shape(p.0.precision),
            px,
            py,
            r,
            view_color(p.0.view),
            WHITE,
        );
    }
    for p in &points {
        let (px, py) = (x.map(p.1), y.map(p.2));
        let label = level_label(p.0.level);
        if on_curve(p.0) {
            c.text(
                px as i32 + 9,
                py as i32 - 18,
                &label,
                2,
                darker(view_color(p.0.view)),
            );
        } else {
            // Off the curve (another precision of a level): a small label below the marker.
            c.text(
                px as i32 + 7,
                py as i32 + 5,
                &label,
                1,
                darker(view_color(p.0.view)),
            );
        }
    }

    // Legend: views (colour), precisions (shape), level abbreviations.
    let lx = right as i32 + 24;
    let mut ly = top as i32;
    c.text(lx, ly, "VIEW", 2, BLACK);
    ly += 24;
    for &view in &views {
        let col = view_color(view);
        c.line(
            (lx as f32, ly as f32 + 7.0),
            (lx as f32 + 26.0, ly as f32 + 7.0),
            2.5,
            col,
        );
        c.marker(
            Shape::Circle,
            lx as f32 + 13.0,
            ly as f32 + 7.0,
            5.0,
            col,
            WHITE,
        );
        c.text(lx + 36, ly, view.name(), 2, BLACK);
        ly += 24;
    }
    ly += 14;
    c.text(lx, ly, "WEAVE", 2, BLACK);
    ly += 24;
    for p in WeavePrecision::ALL {
        if precisions.contains_key(p.name()) {
            c.marker(
                precision_shape(p),
                lx as f32 + 13.0,
                ly as f32 + 7.0,
                5.0,
                MUTED,
                WHITE,
            );
            c.text(lx + 36, ly, p.name(), 2, BLACK);
            ly += 24;
        }
    }
    c.marker(
        Shape::Circle,
        lx as f32 + 13.0,
        ly as f32 + 7.0,
        10.5,
        BLACK,
        WHITE,
    );
    c.marker(
        Shape::Circle,
        lx as f32 + 13.0,
        ly as f32 + 7.0,
        9.0,
        WHITE,
        WHITE,
    );
    c.marker(
        Shape::Circle,
        lx as f32 + 13.0,
        ly as f32 + 7.0,
        5.0,
        MUTED,
        WHITE,
    );
    c.text(lx + 36, ly, "Pareto front", 2, BLACK);
    ly += 38;
    c.text(lx, ly, "LEVEL", 2, BLACK);
    ly += 24;
    for &level in &levels {
        c.text(lx, ly, &level_label(level), 2, BLACK);
        c.text(lx + 48, ly + 4, &level.name(), 1, BLACK);
        ly += 20;
    }
    ly += 12;
    for line in [
        "Curves: rgba16f where",
        "measured, else analytic",
        "(supersampled levels",
        "evaluate the weave",
        "analytically).",
    ] {
        c.text(lx, ly, line, 1, MUTED);
        ly += 11;
    }
    if emin <= FLOOR {
        ly += 10;
        c.text(lx, ly, "Dashed: errors below", 1, MUTED);
        c.text(lx, ly + 11, "1e-4 drawn on it.", 1, MUTED);
    }
    (W, H, c.to_rgba8())
}

fn darker(c: Rgb) -> Rgb {
    [c[0] * 0.6, c[1] * 0.6, c[2] * 0.6]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_printable_ascii_character_has_a_glyph_or_the_fallback() {
        let fallback = glyph('?');
        for c in "0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZx .,:;-+=/()[]%_<>*#'^".chars() {
            assert!(c == '?' || glyph(c) != fallback, "{c:?} has no glyph");
        }
        assert_eq!(glyph('~'), fallback);
    }

    #[test]
    fn log_axis_maps_its_ends_and_ticks_inside() {
        let a = LogAxis::fit(1.0, 1000.0, 0.0, 100.0);
        assert!(a.map(1.0) > 0.0 && a.map(1000.0) < 100.0);
        assert!(a.ticks().iter().any(|t| t.0 == 10.0 && t.1));
        assert_eq!(tick_label(0.001), "0.001");
        assert_eq!(tick_label(20.0), "20");
    }
}
