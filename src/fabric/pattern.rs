//! Weave patterns: which of the two threads is on top in each cell of one repeat.
//!
//! A pattern is a `cols × rows` matrix (at most 8 × 8) of cells. Cell `(i, j)` covers
//! `u ∈ [i, i+1)·s_p/2`, `v ∈ [j, j+1)·s_p/2` of the repeat (one cell is half of the plain weave's
//! repeat `s_p`, as in eq. 2 of the model page). In a *weft-up* cell the horizontal thread (the weft,
//! running along `t` = +u) is on top; in a *warp-up* cell the vertical thread (the warp, along
//! `b` = +v) is. The pattern tiles the plane: a pattern of `cols` cells repeats every
//! `cols·s_p/2` texture units along u.
//!
//! The GPU sees the matrix as 64 bits (`pattern_lo`, `pattern_hi`): bit `8·j + i` set = cell `(i, j)`
//! is weft-up.

/// Largest number of cells along either axis of a pattern.
pub const MAX_CELLS: usize = 8;

/// A weave pattern: a matrix of warp-up / weft-up cells. See the module docs for the conventions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct WeavePattern {
    cols: u8,
    rows: u8,
    /// Bit `8·j + i` set = cell `(i, j)` is weft-up.
    weft_up: u64,
}

impl Default for WeavePattern {
    fn default() -> Self {
        WeavePattern::plain()
    }
}

impl WeavePattern {
    /// The plain weave of the paper (eq. 2): 2 × 2, weft-up where `i + j` is even.
    ///
    /// With `ũ = (u mod s_p) - s_p/2`, cell `i = 0` has `ũ < 0` and `i = 1` has `ũ > 0` (same for
    /// `ṽ`, `j`), so `δ = ũ·ṽ > 0` (weft on top) exactly in cells (0,0) and (1,1).
    pub fn plain() -> Self {
        Self::from_fn(2, 2, |i, j| (i + j) % 2 == 0)
    }

    /// 3/1 twill, 4 × 4: in each row one weft-up cell and three warp-up cells (warp-faced); the
    /// weft-up cell moves one column to the right (+u) per row (+v): weft-up where `i ≡ j (mod 4)`.
    pub fn twill() -> Self {
        Self::from_fn(4, 4, |i, j| i % 4 == j % 4)
    }

    /// 5-harness satin, 5 × 5 (warp-faced, move 2): weft-up where `i ≡ 2j (mod 5)`, so no two
    /// weft-up cells touch, not even diagonally.
    pub fn satin() -> Self {
        Self::from_fn(5, 5, |i, j| i % 5 == (2 * j) % 5)
    }

    /// The named patterns the glTF extension accepts.
    pub const NAMES: [&'static str; 3] = ["plain", "twill", "satin"];

    /// A named pattern (`"plain"`, `"twill"`, `"satin"`), or None.
    pub fn by_name(name: &str) -> Option<Self> {
        match name {
            "plain" => Some(Self::plain()),
            "twill" => Some(Self::twill()),
            "satin" => Some(Self::satin()),
            _ => None,
        }
    }

    /// A pattern whose cell `(i, j)` is weft-up when `weft_up(i, j)`; sizes must be in 1..=8.
    ///
    /// # Panics
    /// On sizes outside 1..=8 (an internal invariant: user input goes through [`Self::from_rows`]).
    pub fn from_fn(cols: usize, rows: usize, weft_up: impl Fn(usize, usize) -> bool) -> Self {
        assert!(
            (1..=MAX_CELLS).contains(&cols) && (1..=MAX_CELLS).contains(&rows),
            "weave pattern size {cols}x{rows} is outside 1x1..8x8"
        );
        let mut bits = 0u64;
        for j in 0..rows {
            for i in 0..cols {
                if weft_up(i, j) {
                    bits |= 1 << (8 * j + i);
                }
            }
        }
        WeavePattern {
            cols: cols as u8,
            rows: rows as u8,
            weft_up: bits,
        }
    }

    /// A custom pattern from rows of characters: string `j` is row `j` (cells with v-index `j`, the
    /// first string is the lowest v), character `i` is column `i` (u-index `i`). `'-'` or `'H'`
    /// (horizontal) = weft-up, `'|'` or `'V'` (vertical) = warp-up; letters in either case.
    /// 1 to 8 rows of 1 to 8 characters, all rows the same length. The error says what is wrong.
    pub fn from_rows<S: AsRef<str>>(rows: &[S]) -> crate::Result<Self> {
        if rows.is_empty() || rows.len() > MAX_CELLS {
            return Err(crate::Error::input(format!(
                "a custom pattern needs 1 to {MAX_CELLS} rows, got {}",
                rows.len()
            )));
        }
        let mut cells: Vec<Vec<bool>> = Vec::with_capacity(rows.len());
        for (j, row) in rows.iter().enumerate() {
            let row = row.as_ref();
            let mut line = Vec::new();
            for c in row.chars() {
                match c {
                    '-' | 'H' | 'h' => line.push(true),
                    '|' | 'V' | 'v' => line.push(false),
                    other => {
                        return Err(crate::Error::input(format!(
                            "row {j} (\"{row}\") has '{other}'; use '-' or 'H' for weft-up \
                             (horizontal thread on top) and '|' or 'V' for warp-up"
                        )))
                    }
                }
            }
            if line.is_empty() || line.len() > MAX_CELLS {
                return Err(crate::Error::input(format!(
                    "row {j} (\"{row}\") has {} cells; rows need 1 to {MAX_CELLS}",
                    line.len()
                )));
            }
            if let Some(first) = cells.first() {
                if first.len() != line.len() {
                    return Err(crate::Error::input(format!(
                        "row {j} (\"{row}\") has {} cells but row 0 has {}; all rows must be equally long",
                        line.len(),
                        first.len()
                    )));
                }
            }
            cells.push(line);
        }
        let cols = cells[0].len();
        Ok(Self::from_fn(cols, cells.len(), |i, j| cells[j][i]))
    }

    /// The pattern as rows of `'-'` (weft-up) and `'|'` (warp-up), row 0 first: the inverse of
    /// [`Self::from_rows`].
    pub fn to_rows(&self) -> Vec<String> {
        (0..self.rows())
            .map(|j| {
                (0..self.cols())
                    .map(|i| {
                        if self.is_weft_up(i as isize, j as isize) {
                            '-'
                        } else {
                            '|'
                        }
                    })
                    .collect()
            })
            .collect()
    }

    /// `"plain"`, `"twill"`, `"satin"`, or the rows of a custom pattern (`"-|/|-"`).
    pub fn name(&self) -> String {
        Self::NAMES
            .iter()
            .find(|n| Self::by_name(n) == Some(*self))
            .map(|n| n.to_string())
            .unwrap_or_else(|| self.to_rows().join("/"))
    }

    /// Cells along u.
    pub fn cols(&self) -> usize {
        self.cols as usize
    }

    /// Cells along v.
    pub fn rows(&self) -> usize {
        self.rows as usize
    }

    /// Is cell `(i, j)` weft-up? Indices wrap around the repeat (negative ones too).
    pub fn is_weft_up(&self, i: isize, j: isize) -> bool {
        let i = i.rem_euclid(self.cols as isize) as u32;
        let j = j.rem_euclid(self.rows as isize) as u32;
        self.weft_up >> (8 * j + i) & 1 == 1
    }

    /// All 64 bits, bit `8·j + i` = cell `(i, j)` weft-up.
    pub fn bits(&self) -> u64 {
        self.weft_up
    }

    /// Bits of rows 0..4 (the GPU's `pattern_lo`).
    pub fn bits_lo(&self) -> u32 {
        self.weft_up as u32
    }

    /// Bits of rows 4..8 (the GPU's `pattern_hi`).
    pub fn bits_hi(&self) -> u32 {
        (self.weft_up >> 32) as u32
    }

    /// Rebuilds a pattern from its GPU form; None when the sizes are outside 1..=8 or a bit is set
    /// outside the matrix.
    pub fn from_bits(cols: u32, rows: u32, lo: u32, hi: u32) -> Option<Self> {
        if !(1..=MAX_CELLS as u32).contains(&cols) || !(1..=MAX_CELLS as u32).contains(&rows) {
            return None;
        }
        let bits = lo as u64 | (hi as u64) << 32;
        let p = Self::from_fn(cols as usize, rows as usize, |i, j| {
            bits >> (8 * j + i) & 1 == 1
        });
        (p.weft_up == bits).then_some(p)
    }

    /// The pattern seen with u mirrored (`u → -u`): column `i` becomes column `cols - 1 - i`.
    pub fn mirrored_u(&self) -> Self {
        let c = self.cols();
        Self::from_fn(c, self.rows(), |i, j| {
            self.is_weft_up((c - 1 - i) as isize, j as isize)
        })
    }

    /// Fraction of the repeat's cells that are weft-up.
    pub fn weft_up_fraction(&self) -> f64 {
        self.weft_up.count_ones() as f64 / (self.cols() * self.rows()) as f64
    }

    /// A short `(i, j)` iterator over all cells, row by row.
    pub fn cells(&self) -> impl Iterator<Item = (usize, usize)> {
        let (c, r) = (self.cols(), self.rows());
        (0..r).flat_map(move |j| (0..c).map(move |i| (i, j)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn named_patterns_round_trip() {
        for name in WeavePattern::NAMES {
            let p = WeavePattern::by_name(name).unwrap();
            assert_eq!(p.name(), name);
            assert_eq!(WeavePattern::from_rows(&p.to_rows()).unwrap(), p);
            assert_eq!(
                WeavePattern::from_bits(p.cols() as u32, p.rows() as u32, p.bits_lo(), p.bits_hi()),
                Some(p)
            );
        }
        assert_eq!(WeavePattern::plain().to_rows(), vec!["-|", "|-"]);
        assert_eq!(
            WeavePattern::twill().to_rows(),
            vec!["-|||", "|-||", "||-|", "|||-"]
        );
        assert_eq!(
            WeavePattern::satin().to_rows(),
            vec!["-||||", "||-||", "||||-", "|-|||", "|||-|"]
        );
    }

    #[test]
    fn custom_rows_are_checked() {
        assert!(WeavePattern::from_rows(&["-|", "|"]).is_err());
        assert!(WeavePattern::from_rows(&["-x"]).is_err());
        assert!(WeavePattern::from_rows::<&str>(&[]).is_err());
        assert!(WeavePattern::from_rows(&["---------"]).is_err());
        let p = WeavePattern::from_rows(&["HV", "vh"]).unwrap();
        assert_eq!(p, WeavePattern::plain());
        let big = WeavePattern::from_rows(&["-|-|-|-|"; 8]).unwrap();
        assert_eq!((big.cols(), big.rows()), (8, 8));
        assert!(big.is_weft_up(6, 7) && !big.is_weft_up(7, 7) && big.is_weft_up(-2, -1));
    }
}
