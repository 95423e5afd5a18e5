//! The weave texture: one full pattern repeat (so it tiles with REPEAT addressing), each mip level
//! built directly by `glsl/weave.comp` with the exact coverage of each texel's footprint, not by
//! downsampling the level above.
//!
//! Texel `(x, y)` of a level of `W × H` texels covers `[x/W, (x+1)/W] × [y/H, (y+1)/H]` of the repeat
//! (row `y = 0` is `v = 0`: sample at `st = (u, v)·cell_per_uv / (cols, rows)`, no flip) and holds
//! `(c_warp, c_weft, s_warp, s_weft)`: the area fractions of warp and weft on top and each
//! weighted by the diffuse shadow factor (see `reference::weave`). These are linear in area, so trilinear and
//! anisotropic filtering of them is again a correct footprint average.

use crate::fabric::coverage::single::{weave_box, Weave};

/// Texels per cell at level 0: enough that a magnified cell (where the point classifier, not the
/// texture, is used) is still smooth, and that the gap of a 10 % gap weave spans 3 texels.
pub const WEAVE_TEXELS_PER_CELL: u32 = 32;

/// Largest difference allowed between a texel of the GPU texture (RGBA16F) and
/// [`weave_texels_cpu`]: one f16 ulp at 1.0 (2^-10: the store rounds to nearest or toward zero,
/// the spec allows either) plus the difference between two f32 evaluations of the same
/// operations (GPU division is 2.5 ulp, products may be fused): a few ulp of coordinates ≤ 8 per
/// boundary, divided by the texel size 1/32 cell, < 1e-4 — taken as 2^-12.
pub const WEAVE_TEXEL_TOLERANCE: f32 = 1.0 / 1024.0 + 1.0 / 4096.0;

/// Push constants of `glsl/weave.comp` (std430 push-constant block, 36 bytes).
///
/// | offset | field | meaning |
/// |---|---|---|
/// | 0  | `pattern_lo: uint` | weft-up bits of rows 0..4, bit `8j + i` = cell (i, j) |
/// | 4  | `pattern_hi: uint` | rows 4..8 |
/// | 8  | `cols: uint` | cells along u, 1..8 |
/// | 12 | `rows: uint` | cells along v, 1..8 |
/// | 16 | `gap: float` | `s_g/s_p`: half the gap, in cells |
/// | 20 | `shadow_dist: float` | `shadow_width/2`, in cells |
/// | 24 | `shadow_strength: float` | |
/// | 28 | `width: uint` | this level's width in texels |
/// | 32 | `height: uint` | this level's height |
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct WeavePush {
    pub pattern_lo: u32,
    pub pattern_hi: u32,
    pub cols: u32,
    pub rows: u32,
    pub gap: f32,
    pub shadow_dist: f32,
    pub shadow_strength: f32,
    pub width: u32,
    pub height: u32,
}

const _: () = {
    assert!(std::mem::size_of::<WeavePush>() == 36);
    assert!(std::mem::offset_of!(WeavePush, gap) == 16);
    assert!(std::mem::offset_of!(WeavePush, width) == 28);
};

impl WeavePush {
    /// The push constants' bytes (little-endian).
    pub fn to_bytes(&self) -> [u8; 36] {
        // The struct is #[repr(C)] and Pod with no padding: its bytes are the push-constant layout.
        bytemuck::bytes_of(self)
            .try_into()
            .expect("the size is asserted at compile time")
    }

    /// The same push constants for another level size.
    pub fn with_size(&self, width: u32, height: u32) -> WeavePush {
        WeavePush {
            width,
            height,
            ..*self
        }
    }
}

/// The recommended level-0 size of a pattern's texture: [`WEAVE_TEXELS_PER_CELL`] per cell
/// (so every texel border lies on a multiple of 1/32 cell: exact in f32).
pub fn weave_level0_size(pattern: &super::WeavePattern) -> (u32, u32) {
    (
        WEAVE_TEXELS_PER_CELL * pattern.cols() as u32,
        WEAVE_TEXELS_PER_CELL * pattern.rows() as u32,
    )
}

/// The size of mip `level` in Vulkan's convention: `max(1, floor(size / 2^level))`.
pub fn weave_level_size(level0: (u32, u32), level: u32) -> (u32, u32) {
    (
        (level0.0 >> level.min(31)).max(1),
        (level0.1 >> level.min(31)).max(1),
    )
}

/// The number of levels of a full mip chain down to 1 × 1.
pub fn weave_mip_count(level0: (u32, u32)) -> u32 {
    32 - level0.0.max(level0.1).max(1).leading_zeros()
}

/// The texels `weave.comp` writes for `push` (`push.width × push.height`, row `y` after row `y-1`),
/// computed on the CPU by the same f32 code (`reference::weave::single::weave_box`), before the
/// GPU's rounding to f16.
pub fn weave_texels_cpu(push: &WeavePush) -> Vec<[f32; 4]> {
    let w = Weave::from_push(push);
    let sx = push.cols as f32 / push.width as f32;
    let sy = push.rows as f32 / push.height as f32;
    let mut out = Vec::with_capacity((push.width * push.height) as usize);
    for y in 0..push.height {
        for x in 0..push.width {
            let c = weave_box(
                &w,
                x as f32 * sx,
                y as f32 * sy,
                (x + 1) as f32 * sx,
                (y + 1) as f32 * sy,
            );
            out.push(c);
        }
    }
    out
}

/// The weave as a summed-area table (`--weave-precision sat`, `WEAVE_SOURCE` 2 of the G-buffer
/// pass): the mean coverage of any axis-aligned box of the weave in four corner look-ups,
/// exact for the coverage averaged over cells of `1/WEAVE_TEXELS_PER_CELL` (the texture's level 0),
/// where a trilinear probe of the mip chain spreads a footprint of about one cell over a tent
/// twice its width.
///
/// The table spans `R × R` repeats ([`WeaveSat::repeats_for`]: 2, or more for weaves of fewer
/// than four cells a side), so that any box narrower than `R − 1` repeats, its corner reduced into
/// the first repeat, lies inside it and its integral is four corners alone. `R − 1` repeats hold
/// four cells, the widest footprint the G-buffer cuts into pieces (`weave_pieces`), so only a
/// footprint taken whole can need the whole-table terms, and the shader takes them once per
/// pixel rather than once per piece. With `W × H` the level-0 size of one repeat, texel
/// `(i, j)`, `i ≤ RW`, `j ≤ RH`, holds the integral over `[0, i/W] × [0, j/H]` (in repeats: a
/// repeat has area 1) of the coverage *minus its mean*: the mean's share is added back exactly,
/// so the table's values stay of the order of one cell's area whatever the box (no cancellation
/// of large sums in f32). Texel `(RW + 1, 0)` holds the mean, texel `(RW + 1, 1)` holds `R` (in
/// its first channel). Computed here in f64 from the exact box coverages
/// ([`crate::fabric::coverage::double::weave_box`]), stored RGBA32F.
#[derive(Clone, Debug, PartialEq)]
pub struct WeaveSat {
    /// `RW + 2` texels.
    pub width: u32,
    /// `RH + 1` texels.
    pub height: u32,
    /// Row `j` after row `j - 1`.
    pub texels: Vec<[f32; 4]>,
}

impl WeaveSat {
    /// The fewest repeats a table spans along each axis (a thread-colour table's count).
    pub const REPEATS: u32 = 2;

    /// The repeats `R` a weave's table spans along each axis: at least [`Self::REPEATS`], and
    /// `1 + 4 / cells` for a repeat of fewer cells a side, so that every piece of a footprint
    /// under four cells (`weave_pieces` of weave.glsl cuts no wider one) lies inside the table.
    pub fn repeats_for(cols: u32, rows: u32) -> u32 {
        let cells = cols.min(rows).max(1);
        Self::REPEATS.max(1 + 4u32.div_ceil(cells))
    }

    /// The table's size in texels for a weave of `cols × rows` cells whose repeat is `level0`
    /// texels (the weave texture's level 0): `RW + 2` by `RH + 1`.
    pub fn size_for(cols: u32, rows: u32, level0: (u32, u32)) -> (u32, u32) {
        let r = Self::repeats_for(cols, rows);
        (r * level0.0.max(1) + 2, r * level0.1.max(1) + 1)
    }

    /// The table of the weave of `push` at `push.width × push.height` cells per repeat (the
    /// weave texture's level 0, [`weave_level0_size`]).
    pub fn new(push: &WeavePush) -> WeaveSat {
        use crate::fabric::coverage::double;
        let w = double::Weave::from_push(push);
        let (cols, rows) = (push.cols.max(1) as f64, push.rows.max(1) as f64);
        let (nw, nh) = (push.width.max(1), push.height.max(1));
        let r = Self::repeats_for(push.cols, push.rows);
        let (tw, th) = (r * nw, r * nh);
        let mean = double::weave_box(&w, 0.0, 0.0, cols, rows);
        let (width, height) = Self::size_for(push.cols, push.rows, (nw, nh));
        let mut texels = vec![[0f32; 4]; (width * height) as usize];
        for j in 1..=th {
            let y = j as f64 / nh as f64;
            for i in 1..=tw {
                let x = i as f64 / nw as f64;
                let c = double::weave_box(&w, 0.0, 0.0, x * cols, y * rows);
                texels[(j * width + i) as usize] =
                    std::array::from_fn(|k| ((c[k] - mean[k]) * x * y) as f32);
            }
        }
        texels[tw as usize + 1] = mean.map(|m| m as f32);
        texels[(width + tw + 1) as usize] = [r as f32, 0.0, 0.0, 0.0];
        WeaveSat {
            width,
            height,
            texels,
        }
    }

    fn texel(&self, i: i32, j: i32) -> [f32; 4] {
        let i = i.clamp(0, self.width as i32 - 1) as u32;
        let j = j.clamp(0, self.height as i32 - 1) as u32;
        self.texels[(j * self.width + i) as usize]
    }

    /// The repeats `R` the table spans along each axis (texel `(RW + 1, 1)`).
    pub fn repeats(&self) -> f32 {
        self.texel(self.width as i32 - 1, 1)[0]
    }

    /// The mean of the table's value (texel `(RW + 1, 0)`).
    pub fn mean(&self) -> [f32; 4] {
        self.texel(self.width as i32 - 1, 0)
    }

    /// The table at `q` in texel-corner units (`[0, RW] × [0, RH]`): bilinear between the four
    /// corners around it, exact for the texel-averaged coverage (`sat_corner` of
    /// surface.glsl, f32 as there).
    pub fn corner(&self, q: [f32; 2]) -> [f32; 4] {
        let n = [self.width as i32 - 2, self.height as i32 - 1];
        let i = [
            (q[0].floor() as i32).clamp(0, n[0] - 1),
            (q[1].floor() as i32).clamp(0, n[1] - 1),
        ];
        let f = [
            (q[0] - i[0] as f32).clamp(0.0, 1.0),
            (q[1] - i[1] as f32).clamp(0.0, 1.0),
        ];
        let (a, b) = (self.texel(i[0], i[1]), self.texel(i[0] + 1, i[1]));
        let (c, d) = (self.texel(i[0], i[1] + 1), self.texel(i[0] + 1, i[1] + 1));
        let mix = |x: f32, y: f32, t: f32| x * (1.0 - t) + y * t;
        std::array::from_fn(|k| mix(mix(a[k], b[k], f[0]), mix(c[k], d[k], f[0]), f[1]))
    }

    /// Where the box `[lo, hi]` lies in the table: `lo` reduced into the first repeat and
    /// `hi = R·X + u1` (X whole tables); `(q0, q1, X)`, the corners in texel-corner units.
    fn place(&self, lo: [f32; 2], hi: [f32; 2]) -> ([f32; 2], [f32; 2], [f32; 2]) {
        let n = [(self.width - 2) as f32, (self.height - 1) as f32];
        let r = self.repeats();
        let ext = [hi[0] - lo[0], hi[1] - lo[1]];
        let l = [lo[0] - lo[0].floor(), lo[1] - lo[1].floor()];
        let h = [l[0] + ext[0], l[1] + ext[1]];
        let whole = [(h[0] / r).floor(), (h[1] / r).floor()];
        let q0 = [l[0] * n[0] / r, l[1] * n[1] / r];
        let q1 = [
            (h[0] - r * whole[0]) * n[0] / r,
            (h[1] - r * whole[1]) * n[1] / r,
        ];
        (q0, q1, whole)
    }

    /// The four corners' part of the integral of coverage minus mean over `[lo, hi]`,
    /// `T(u1,v1) − T(u1,v0) − T(u0,v1) + T(u0,v0)`: all of it for a box narrower than `R − 1`
    /// repeats (`sat_corners` of surface.glsl).
    pub fn box_corners(&self, lo: [f32; 2], hi: [f32; 2]) -> [f32; 4] {
        let (q0, q1, _) = self.place(lo, hi);
        let t11 = self.corner(q1);
        let t10 = self.corner([q1[0], q0[1]]);
        let t01 = self.corner([q0[0], q1[1]]);
        let t00 = self.corner(q0);
        std::array::from_fn(|k| t11[k] - t10[k] - t01[k] + t00[k])
    }

    /// The whole tables' part, `X·(T(R,v1) − T(R,v0)) + Y·(T(u1,R) − T(u0,R))` (a whole table
    /// of coverage minus mean is 0): 0 for a box narrower than `R − 1` repeats (`sat_whole` of
    /// surface.glsl).
    pub fn box_whole(&self, lo: [f32; 2], hi: [f32; 2]) -> [f32; 4] {
        let n = [(self.width - 2) as f32, (self.height - 1) as f32];
        let (q0, q1, whole) = self.place(lo, hi);
        let mut sum = [0f32; 4];
        if whole[0] > 0.0 {
            let (a, b) = (self.corner([n[0], q1[1]]), self.corner([n[0], q0[1]]));
            for k in 0..4 {
                sum[k] += whole[0] * (a[k] - b[k]);
            }
        }
        if whole[1] > 0.0 {
            let (a, b) = (self.corner([q1[0], n[1]]), self.corner([q0[0], n[1]]));
            for k in 0..4 {
                sum[k] += whole[1] * (a[k] - b[k]);
            }
        }
        sum
    }

    /// The mean coverage over the box `[lo, hi]` of st (a repeat is 1 unit; any size and place,
    /// `hi > lo`): the mean plus the corners' and the whole tables' parts over the box's area
    /// (`sat_box` of surface.glsl).
    pub fn box_mean(&self, lo: [f32; 2], hi: [f32; 2]) -> [f32; 4] {
        let (c, w) = (self.box_corners(lo, hi), self.box_whole(lo, hi));
        let area = ((hi[0] - lo[0]) * (hi[1] - lo[1])).max(1e-30);
        let mean = self.mean();
        std::array::from_fn(|k| mean[k] + (c[k] + w[k]) / area)
    }
}

/// Thread-by-thread colours as the G-buffer pass reads them (`thread_colour` of surface.glsl):
/// the material's record in the thread-colour buffer, vec4s:
///
/// | vec4 | holds |
/// |---|---|
/// | 0 | warp colours, weft colours, the colour repeat in cells along u and v |
/// | 1 | texels per cell, the table's width and height, 0 |
/// | 2.. | the warp colours, then the weft colours (linear rgb, 0) |
/// | then | the table, row after row |
///
/// The colour repeat is the least common multiple of the weave's repeat and each sequence's
/// length. The table is a [`WeaveSat`] (same layout, same reader: `sat_box` of surface.glsl, twin
/// [`WeaveSat::box_mean`] with st in colour repeats) of `(s_warp·c_warp + s_weft·c_weft, s_warp +
/// s_weft)`, each thread's shadow-weighted area times its colour, built in f64 from the exact
/// box coverages of its texels (a texel lies in one cell, so in one warp and one weft thread).
#[derive(Clone, Debug, PartialEq)]
pub struct ThreadColourTable {
    pub warp: Vec<[f32; 3]>,
    pub weft: Vec<[f32; 3]>,
    /// The colour repeat, cells along u and v.
    pub repeat_cells: [u32; 2],
    pub texels_per_cell: u32,
    pub table: WeaveSat,
}

impl ThreadColourTable {
    /// The longest colour repeat (cells along either side) weft builds a table for: a table of
    /// `(2·512 + 2) × (2·512 + 1)` texels (16 MiB) at one texel per cell.
    pub const MAX_REPEAT_CELLS: u32 = 512;
    /// Texels per cell, at most: a quarter of a thread's width at the gaps of the presets.
    pub const MAX_TEXELS_PER_CELL: u32 = 8;

    /// The colour repeat of `params` in cells (along u, along v).
    pub fn repeat_cells(params: &super::FabricParams) -> [u32; 2] {
        fn gcd(a: u32, b: u32) -> u32 {
            if b == 0 {
                a
            } else {
                gcd(b, a % b)
            }
        }
        let lcm = |a: u32, b: u32| a / gcd(a, b) * b;
        [
            lcm(
                params.pattern.cols() as u32,
                params.warp_colours.len().max(1) as u32,
            ),
            lcm(
                params.pattern.rows() as u32,
                params.weft_colours.len().max(1) as u32,
            ),
        ]
    }

    /// An error when a sequence of `params` is longer than [`super::MAX_THREAD_COLOURS`] or its
    /// colour repeat longer than [`Self::MAX_REPEAT_CELLS`] (instead of [`super::FabricParams::sanitized`]
    /// cutting the sequence short).
    pub fn check(params: &super::FabricParams) -> crate::Result<()> {
        let p = params;
        let longest = p.warp_colours.len().max(p.weft_colours.len());
        if longest > super::MAX_THREAD_COLOURS {
            return Err(crate::Error::input(format!(
                "a colour sequence has {longest} colours, more than {}: give one period of it",
                super::MAX_THREAD_COLOURS
            )));
        }
        let [wc, hc] = Self::repeat_cells(p);
        if wc.max(hc) > Self::MAX_REPEAT_CELLS {
            return Err(crate::Error::input(format!(
                "the thread colours repeat every {wc} x {hc} cells (the least common multiple of the weave's {} x {} and the sequences' {} warp and {} weft colours), longer than {} cells: make each sequence's length a multiple or a divisor of the weave's repeat, or shorten it",
                p.pattern.cols(),
                p.pattern.rows(),
                p.warp_colours.len(),
                p.weft_colours.len(),
                Self::MAX_REPEAT_CELLS
            )));
        }
        Ok(())
    }

    /// The table of `params` (None without colour sequences); an error when the colour repeat
    /// is longer than [`Self::MAX_REPEAT_CELLS`].
    pub fn new(params: &super::FabricParams) -> crate::Result<Option<ThreadColourTable>> {
        use crate::fabric::coverage::double;
        let p = params.sanitized();
        if !p.has_thread_colours() {
            return Ok(None);
        }
        Self::check(&p)?;
        let [wc, hc] = Self::repeat_cells(&p);
        let c = (Self::MAX_REPEAT_CELLS / wc.max(hc)).clamp(1, Self::MAX_TEXELS_PER_CELL);
        let w = double::Weave::from_push(&p.weave_push(1, 1));
        let r = WeaveSat::REPEATS;
        let (nw, nh) = (wc * c, hc * c);
        let (tw, th) = (r * nw, r * nh);
        let (width, height) = (tw + 2, th + 1);
        // Each texel's integral (in colour repeats², a repeat has area 1), then the prefix sums.
        let area = 1.0 / (nw as f64 * nh as f64);
        let mut sums = vec![[0f64; 4]; ((tw + 1) * (th + 1)) as usize];
        let at = |i: u32, j: u32| (j * (tw + 1) + i) as usize;
        for j in 0..th {
            let pick = (j / c) as usize;
            let cf = p.thread_colour(false, pick);
            for i in 0..tw {
                let thread = (i / c) as usize;
                let cw = p.thread_colour(true, thread);
                let (x0, y0) = (i as f64 / c as f64, j as f64 / c as f64);
                let b = double::weave_box(&w, x0, y0, x0 + 1.0 / c as f64, y0 + 1.0 / c as f64);
                let v: [f64; 4] = std::array::from_fn(|k| {
                    if k < 3 {
                        (b[2] * cw[k] as f64 + b[3] * cf[k] as f64) * area
                    } else {
                        (b[2] + b[3]) * area
                    }
                });
                let (left, down, diag) = (sums[at(i, j + 1)], sums[at(i + 1, j)], sums[at(i, j)]);
                sums[at(i + 1, j + 1)] =
                    std::array::from_fn(|k| v[k] + left[k] + down[k] - diag[k]);
            }
        }
        let mean = sums[at(nw, nh)];
        let mut texels = vec![[0f32; 4]; (width * height) as usize];
        for j in 1..=th {
            let y = j as f64 / nh as f64;
            for i in 1..=tw {
                let x = i as f64 / nw as f64;
                let s = sums[at(i, j)];
                texels[(j * width + i) as usize] =
                    std::array::from_fn(|k| (s[k] - mean[k] * x * y) as f32);
            }
        }
        texels[tw as usize + 1] = mean.map(|m| m as f32);
        texels[(width + tw + 1) as usize] = [r as f32, 0.0, 0.0, 0.0];
        Ok(Some(ThreadColourTable {
            warp: (0..p.warp_colours.len().max(1))
                .map(|i| p.thread_colour(true, i))
                .collect(),
            weft: (0..p.weft_colours.len().max(1))
                .map(|j| p.thread_colour(false, j))
                .collect(),
            repeat_cells: [wc, hc],
            texels_per_cell: c,
            table: WeaveSat {
                width,
                height,
                texels,
            },
        }))
    }

    /// The record as the buffer holds it (see the type's docs).
    pub fn record(&self) -> Vec<[f32; 4]> {
        let mut out =
            Vec::with_capacity(2 + self.warp.len() + self.weft.len() + self.table.texels.len());
        out.push([
            self.warp.len() as f32,
            self.weft.len() as f32,
            self.repeat_cells[0] as f32,
            self.repeat_cells[1] as f32,
        ]);
        out.push([
            self.texels_per_cell as f32,
            self.table.width as f32,
            self.table.height as f32,
            0.0,
        ]);
        out.extend(
            self.warp
                .iter()
                .chain(&self.weft)
                .map(|c| [c[0], c[1], c[2], 0.0]),
        );
        out.extend_from_slice(&self.table.texels);
        out
    }

    /// The footprint's shadow-weighted thread colour over the box `[lo, hi]` of st (weave
    /// repeats, reduced into the colour repeat): `thread_colour` of surface.glsl (f32, as
    /// there), for `cols x rows` weave cells. `cov`: the box's coverage (used within one cell);
    /// `coverage(a, b)`: the weave's mean coverage over a box of st (`weave_cells_coverage`: the
    /// weave's table or the analytic weave), used per cell over two to four cells.
    #[allow(clippy::too_many_arguments)]
    pub fn colour(
        &self,
        cols: u32,
        rows: u32,
        lo: [f32; 2],
        hi: [f32; 2],
        cov: [f32; 4],
        coverage: &dyn Fn([f32; 2], [f32; 2]) -> [f32; 4],
        fallback: [f32; 3],
    ) -> [f32; 3] {
        let cells = [cols.max(1) as f32, rows.max(1) as f32];
        let c0 = [(lo[0] * cells[0]).floor(), (lo[1] * cells[1]).floor()];
        let span = [
            ((hi[0] * cells[0]).ceil() - 1.0 - c0[0]).max(0.0),
            ((hi[1] * cells[1]).ceil() - 1.0 - c0[1]).max(0.0),
        ];
        let mix = |cell: [f32; 2], c: [f32; 4]| -> [f32; 4] {
            let wrap = |x: f32, n: usize| (x - n as f32 * (x / n as f32).floor()) as usize % n;
            let cw = self.warp[wrap(cell[0], self.warp.len())];
            let cf = self.weft[wrap(cell[1], self.weft.len())];
            [
                c[2] * cw[0] + c[3] * cf[0],
                c[2] * cw[1] + c[3] * cf[1],
                c[2] * cw[2] + c[3] * cf[2],
                c[2] + c[3],
            ]
        };
        let mixed: [f32; 4] = if span == [0.0, 0.0] {
            mix(c0, cov)
        } else if span[0] <= 1.0 && span[1] <= 1.0 {
            let mut m = [0f32; 4];
            for j in 0..=span[1] as u32 {
                for i in 0..=span[0] as u32 {
                    let cell = [c0[0] + i as f32, c0[1] + j as f32];
                    let a = [lo[0].max(cell[0] / cells[0]), lo[1].max(cell[1] / cells[1])];
                    let b = [
                        hi[0].min((cell[0] + 1.0) / cells[0]),
                        hi[1].min((cell[1] + 1.0) / cells[1]),
                    ];
                    if b[0] > a[0] && b[1] > a[1] {
                        let v = mix(cell, coverage(a, b));
                        let area = (b[0] - a[0]) * (b[1] - a[1]);
                        for k in 0..4 {
                            m[k] += area * v[k];
                        }
                    }
                }
            }
            let area = ((hi[0] - lo[0]) * (hi[1] - lo[1])).max(1e-30);
            m.map(|x| x / area)
        } else {
            let scale = [
                cells[0] / self.repeat_cells[0] as f32,
                cells[1] / self.repeat_cells[1] as f32,
            ];
            self.table.box_mean(
                [lo[0] * scale[0], lo[1] * scale[1]],
                [hi[0] * scale[0], hi[1] * scale[1]],
            )
        };
        if mixed[3] > 1e-4 {
            std::array::from_fn(|k| (mixed[k] / mixed[3]).clamp(0.0, 1.0))
        } else {
            fallback
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fabric::{FabricParams, WeavePattern};

    #[test]
    fn sizes() {
        assert_eq!(weave_level0_size(&WeavePattern::plain()), (64, 64));
        assert_eq!(weave_level0_size(&WeavePattern::satin()), (160, 160));
        assert_eq!(weave_mip_count((160, 160)), 8);
        assert_eq!(weave_mip_count((64, 64)), 7);
        assert_eq!(weave_mip_count((1, 1)), 1);
        assert_eq!(weave_level_size((160, 160), 6), (2, 2));
        assert_eq!(weave_level_size((64, 128), 7), (1, 1));
    }

    #[test]
    fn the_last_level_is_the_repeat_average() {
        let p = FabricParams::default();
        let t = weave_texels_cpu(&p.weave_push(1, 1));
        let g = (p.gap / p.repeat) as f64;
        let cw = (1.0 - 4.0 * g * g) / 2.0;
        assert!(
            (t[0][0] as f64 - cw).abs() < 1e-6 && (t[0][1] as f64 - cw).abs() < 1e-6,
            "{t:?}"
        );
    }
}
