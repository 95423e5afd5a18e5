//! Weaving drafts: the WIF file (Weaving Information File, version 1.1) that weaving programs
//! export, read into a [`WeavePattern`] and the thread colours.
//!
//! A WIF is an INI-style text file: `[SECTION]` headers and `key=value` lines, `;` comments,
//! section and key names in any case. What is read:
//!
//! | section | keys | meaning |
//! |---|---|---|
//! | `[WIF]` | `Version` | must be there (it says the file is a WIF) |
//! | `[WEAVING]` | `Shafts`, `Treadles`, `Rising Shed` | how many; `Rising Shed=false`: a tie-up says which shafts *sink* |
//! | `[WARP]`, `[WEFT]` | `Threads`, `Color` | how many threads (picks); the default colour index |
//! | `[THREADING]` | `thread=shaft[,shaft…]` | which shaft(s) each warp thread goes through |
//! | `[TIEUP]` | `treadle=shaft[,shaft…]` | which shafts each treadle lifts |
//! | `[TREADLING]` | `pick=treadle[,treadle…]` | which treadles each pick presses |
//! | `[LIFTPLAN]` | `pick=shaft[,shaft…]` | which shafts each pick lifts (instead of tie-up and treadling) |
//! | `[COLOR PALETTE]` | `Range=min,max` | the scale of the colour table (default 0,255) |
//! | `[COLOR TABLE]` | `index=r,g,b` | display (sRGB) colours |
//! | `[WARP COLORS]`, `[WEFT COLORS]` | `thread=index` | a colour per thread where it is not the default |
//!
//! Warp thread `t` is up on pick `p` when one of its shafts is lifted on `p`. Thread 1 is column 0
//! of the pattern (the lowest u), pick 1 is row 0 (the lowest v); a cell is weft-up where the warp
//! thread is down. The interlacement's repeat is the smallest period along each axis with which
//! the drawdown repeats itself over the whole draft; the woven model holds repeats up to
//! [`MAX_CELLS`] × [`MAX_CELLS`], and a draft whose interlacement repeats over more is refused
//! with its repeat named (colour stripes may be any length: they are colours, not the weave).
//! Every other section (notes, spacing, thickness, private sections) is ignored.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use super::{WeavePattern, MAX_CELLS};
use crate::Error;

/// A draft read from a WIF: the weave and the thread colours.
#[derive(Clone, Debug, PartialEq)]
pub struct Draft {
    /// The interlacement's repeat (at most 8 × 8 cells).
    pub pattern: WeavePattern,
    /// Linear RGB of every warp thread, thread 1 first; empty when the draft gives no colours.
    pub warp_colours: Vec<[f32; 3]>,
    /// Linear RGB of every pick, pick 1 first; empty when the draft gives no colours.
    pub weft_colours: Vec<[f32; 3]>,
    /// Warp threads and picks in the draft (the whole drawdown, not the repeat).
    pub threads: usize,
    pub picks: usize,
}

/// One `key=value` line with its line number (1-based), for messages.
struct Entry {
    key: String,
    value: String,
    line: usize,
}

struct Wif<'a> {
    name: &'a str,
    sections: BTreeMap<String, Vec<Entry>>,
}

impl<'a> Wif<'a> {
    fn parse(text: &str, name: &'a str) -> crate::Result<Wif<'a>> {
        let mut sections: BTreeMap<String, Vec<Entry>> = BTreeMap::new();
        let mut current: Option<String> = None;
        for (n, raw) in text.lines().enumerate() {
            let line = raw.trim().trim_start_matches('\u{feff}');
            if line.is_empty() || line.starts_with(';') {
                continue;
            }
            if let Some(rest) = line.strip_prefix('[') {
                let Some(end) = rest.find(']') else {
                    return Err(Error::input(format!(
                        "{name}, line {}: section header '{line}' has no closing ']'",
                        n + 1
                    )));
                };
                let section = rest[..end].trim().to_ascii_uppercase();
                sections.entry(section.clone()).or_default();
                current = Some(section);
                continue;
            }
            let Some(section) = &current else {
                return Err(Error::input(format!(
                    "{name}, line {}: '{line}' comes before any [SECTION]; is this a WIF file?",
                    n + 1
                )));
            };
            let Some((key, value)) = line.split_once('=') else {
                // Free text (a [NOTES] paragraph, say) belongs to sections weft ignores.
                continue;
            };
            sections
                .get_mut(section)
                .expect("inserted above")
                .push(Entry {
                    key: key.trim().to_ascii_lowercase(),
                    value: value.trim().to_string(),
                    line: n + 1,
                });
        }
        if !sections.contains_key("WIF") {
            return Err(Error::input(format!(
                "{name} has no [WIF] section, so it is not a Weaving Information File; export the draft as WIF (version 1.1) from the weaving program"
            )));
        }
        Ok(Wif { name, sections })
    }

    fn has(&self, section: &str) -> bool {
        self.sections.contains_key(section)
    }

    fn entries(&self, section: &str) -> &[Entry] {
        self.sections.get(section).map_or(&[], Vec::as_slice)
    }

    fn value(&self, section: &str, key: &str) -> Option<&Entry> {
        self.entries(section).iter().find(|e| e.key == key)
    }

    fn err(&self, section: &str, line: usize, msg: impl std::fmt::Display) -> Error {
        Error::input(format!("{}, [{section}] line {line}: {msg}", self.name))
    }

    /// A positive count `key` of `section`, required.
    fn count(&self, section: &str, key: &str, what: &str) -> crate::Result<usize> {
        let Some(e) = self.value(section, key) else {
            return Err(Error::input(format!(
                "{}: [{section}] has no '{key}=' (the number of {what}); every WIF names it",
                self.name
            )));
        };
        match e.value.parse::<usize>() {
            Ok(n) if (1..=1 << 20).contains(&n) => Ok(n),
            _ => Err(self.err(
                section,
                e.line,
                format!(
                    "{key}={} is not a number of {what} in 1..={}",
                    e.value,
                    1 << 20
                ),
            )),
        }
    }

    /// A number in `1..=max` naming a thread, pick, shaft or treadle.
    fn index(
        &self,
        section: &str,
        line: usize,
        text: &str,
        what: &str,
        max: usize,
    ) -> crate::Result<usize> {
        match text.trim().parse::<usize>() {
            Ok(n) if (1..=max).contains(&n) => Ok(n),
            Ok(n) => Err(self.err(
                section,
                line,
                format!("{what} {n} is out of range: the draft has {max} {what}s (1 to {max})"),
            )),
            Err(_) => Err(self.err(
                section,
                line,
                format!("'{}' is not a {what} number", text.trim()),
            )),
        }
    }

    /// `section`'s lines `key=a,b,c` as key (1..=keys) → set of values (1..=values). A value of
    /// 0 or an empty list means none (some programs write `0` for an unthreaded thread).
    fn lists(
        &self,
        section: &str,
        key_what: &str,
        keys: usize,
        value_what: &str,
        values: usize,
    ) -> crate::Result<BTreeMap<usize, BTreeSet<usize>>> {
        let mut out = BTreeMap::new();
        for e in self.entries(section) {
            let k = self.index(section, e.line, &e.key, key_what, keys)?;
            let mut set = BTreeSet::new();
            for v in e.value.split(',').map(str::trim).filter(|v| !v.is_empty()) {
                if v == "0" {
                    continue;
                }
                set.insert(self.index(section, e.line, v, value_what, values)?);
            }
            out.insert(k, set);
        }
        Ok(out)
    }

    fn bool(&self, section: &str, key: &str, default: bool) -> crate::Result<bool> {
        match self.value(section, key) {
            None => Ok(default),
            Some(e) => match e.value.to_ascii_lowercase().as_str() {
                "true" | "yes" | "on" | "1" => Ok(true),
                "false" | "no" | "off" | "0" => Ok(false),
                other => Err(self.err(
                    section,
                    e.line,
                    format!("{key}={other} is not true or false"),
                )),
            },
        }
    }

    /// The colour table, index → linear RGB; empty when the draft has none.
    fn colour_table(&self) -> crate::Result<BTreeMap<usize, [f32; 3]>> {
        let (lo, hi) = match self.value("COLOR PALETTE", "range") {
            None => (0.0, 255.0),
            Some(e) => {
                let parts: Vec<Option<f64>> =
                    e.value.split(',').map(|p| p.trim().parse().ok()).collect();
                match parts[..] {
                    [Some(lo), Some(hi)] if hi > lo && lo.is_finite() && hi.is_finite() => (lo, hi),
                    _ => {
                        return Err(self.err(
                            "COLOR PALETTE",
                            e.line,
                            format!("Range={} is not 'min,max' with min < max", e.value),
                        ))
                    }
                }
            }
        };
        let mut table = BTreeMap::new();
        for e in self.entries("COLOR TABLE") {
            let index = self.index("COLOR TABLE", e.line, &e.key, "colour", usize::MAX)?;
            let parts: Vec<Option<f64>> =
                e.value.split(',').map(|p| p.trim().parse().ok()).collect();
            let [Some(r), Some(g), Some(b)] = parts[..] else {
                return Err(self.err(
                    "COLOR TABLE",
                    e.line,
                    format!("colour {index} = '{}' is not three numbers r,g,b", e.value),
                ));
            };
            let mut rgb = [0.0f32; 3];
            for (out, v) in rgb.iter_mut().zip([r, g, b]) {
                if !(lo..=hi).contains(&v) {
                    return Err(self.err(
                        "COLOR TABLE",
                        e.line,
                        format!(
                            "colour {index} has {v}, outside the palette's range {lo}..{hi} ([COLOR PALETTE] Range)"
                        ),
                    ));
                }
                *out = crate::color::srgb_decode(((v - lo) / (hi - lo)) as f32);
            }
            table.insert(index, rgb);
        }
        Ok(table)
    }

    /// Every thread's colour in `colours_section` (or the `[side]` default), linear; empty when
    /// the draft names no colour for this side at all.
    fn thread_colours(
        &self,
        side: &str,
        colours_section: &str,
        count: usize,
        table: &BTreeMap<usize, [f32; 3]>,
    ) -> crate::Result<Vec<[f32; 3]>> {
        let lookup = |section: &str, line: usize, text: &str| -> crate::Result<[f32; 3]> {
            let i = self.index(section, line, text, "colour", usize::MAX)?;
            table.get(&i).copied().ok_or_else(|| {
                self.err(
                    section,
                    line,
                    format!("colour {i} is not in the [COLOR TABLE]; add it there or use one of its indices"),
                )
            })
        };
        let default = match self.value(side, "color") {
            Some(e) => Some(lookup(side, e.line, &e.value)?),
            None => None,
        };
        let mut per: BTreeMap<usize, [f32; 3]> = BTreeMap::new();
        for e in self.entries(colours_section) {
            let t = self.index(colours_section, e.line, &e.key, "thread", count)?;
            per.insert(t, lookup(colours_section, e.line, &e.value)?);
        }
        if default.is_none() && per.is_empty() {
            return Ok(Vec::new());
        }
        (1..=count)
            .map(|t| {
                per.get(&t).copied().or(default).ok_or_else(|| {
                    Error::input(format!(
                        "{}: thread {t} has no colour in [{colours_section}] and [{side}] has no default 'Color='",
                        self.name
                    ))
                })
            })
            .collect()
    }
}

/// The smallest period with which `line(k)` repeats over `0..n`.
fn period<T: PartialEq>(n: usize, line: impl Fn(usize) -> T) -> usize {
    (1..=n)
        .find(|&p| (0..n - p).all(|k| line(k) == line(k + p)))
        .unwrap_or(n)
}

impl Draft {
    /// Reads a WIF from its text; `name` (a path) goes into every message.
    pub fn parse(text: &str, name: &str) -> crate::Result<Draft> {
        let wif = Wif::parse(text, name)?;
        let threads = wif.count("WARP", "threads", "warp threads")?;
        let picks = wif.count("WEFT", "threads", "weft threads (picks)")?;
        let shafts = wif.count("WEAVING", "shafts", "shafts")?;
        if !wif.has("THREADING") {
            return Err(Error::input(format!(
                "{name} has no [THREADING]: the draft does not say which shaft each warp thread is on"
            )));
        }
        let threading = wif.lists("THREADING", "warp thread", threads, "shaft", shafts)?;
        let lifts: BTreeMap<usize, BTreeSet<usize>> = if wif.has("LIFTPLAN") {
            wif.lists("LIFTPLAN", "pick", picks, "shaft", shafts)?
        } else if wif.has("TIEUP") && wif.has("TREADLING") {
            let treadles = wif.count("WEAVING", "treadles", "treadles")?;
            let tieup = wif.lists("TIEUP", "treadle", treadles, "shaft", shafts)?;
            let treadling = wif.lists("TREADLING", "pick", picks, "treadle", treadles)?;
            let rising = wif.bool("WEAVING", "rising shed", true)?;
            treadling
                .into_iter()
                .map(|(pick, pressed)| {
                    let tied: BTreeSet<usize> = pressed
                        .iter()
                        .flat_map(|t| tieup.get(t).into_iter().flatten().copied())
                        .collect();
                    let lifted = if rising {
                        tied
                    } else {
                        (1..=shafts).filter(|s| !tied.contains(s)).collect()
                    };
                    (pick, lifted)
                })
                .collect()
        } else {
            return Err(Error::input(format!(
                "{name} has neither a [LIFTPLAN] nor a [TIEUP] with a [TREADLING]: the draft does not say which shafts each pick lifts"
            )));
        };
        let none = BTreeSet::new();
        let warp_up = |t: usize, p: usize| -> bool {
            let on = threading.get(&(t + 1)).unwrap_or(&none);
            let lifted = lifts.get(&(p + 1)).unwrap_or(&none);
            !on.is_disjoint(lifted)
        };
        let cols = period(threads, |t| {
            (0..picks).map(|p| warp_up(t, p)).collect::<Vec<_>>()
        });
        let rows = period(picks, |p| {
            (0..threads).map(|t| warp_up(t, p)).collect::<Vec<_>>()
        });
        if cols > MAX_CELLS || rows > MAX_CELLS {
            return Err(Error::input(format!(
                "{name}: the weave repeats every {cols} warp threads x {rows} picks; the woven model holds a repeat of at most {MAX_CELLS} x {MAX_CELLS} cells (the draft is {threads} x {picks}); use a draft whose interlacement repeats within {MAX_CELLS} x {MAX_CELLS} (its colour stripes may be any length)"
            )));
        }
        let pattern = WeavePattern::from_fn(cols, rows, |i, j| !warp_up(i, j));
        let table = wif.colour_table()?;
        let warp_colours = wif.thread_colours("WARP", "WARP COLORS", threads, &table)?;
        let weft_colours = wif.thread_colours("WEFT", "WEFT COLORS", picks, &table)?;
        Ok(Draft {
            pattern,
            warp_colours,
            weft_colours,
            threads,
            picks,
        })
    }

    /// Reads a WIF file.
    pub fn load(path: &Path) -> crate::Result<Draft> {
        let bytes = std::fs::read(path).map_err(|e| {
            Error::input(format!("cannot read the draft '{}': {e}", path.display()))
        })?;
        // WIFs from older programs are Latin-1 in their notes; the sections weft reads are ASCII.
        let text = String::from_utf8_lossy(&bytes);
        Draft::parse(&text, &path.display().to_string())
    }

    /// The mean linear colour of the warp threads (what the far field sees), if the draft has
    /// warp colours.
    pub fn mean_warp_colour(&self) -> Option<[f32; 3]> {
        mean(&self.warp_colours)
    }

    /// The mean linear colour of the picks, if the draft has weft colours.
    pub fn mean_weft_colour(&self) -> Option<[f32; 3]> {
        mean(&self.weft_colours)
    }

    /// How many different colours the warp (`true`) or the weft carries.
    pub fn colour_count(&self, warp: bool) -> usize {
        let list = if warp {
            &self.warp_colours
        } else {
            &self.weft_colours
        };
        let mut seen: Vec<[u32; 3]> = list.iter().map(|c| c.map(f32::to_bits)).collect();
        seen.sort_unstable();
        seen.dedup();
        seen.len()
    }
}

fn mean(colours: &[[f32; 3]]) -> Option<[f32; 3]> {
    if colours.is_empty() {
        return None;
    }
    let mut sum = [0.0f64; 3];
    for c in colours {
        for k in 0..3 {
            sum[k] += c[k] as f64;
        }
    }
    Some(sum.map(|s| (s / colours.len() as f64) as f32))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A WIF with the given threading, tie-up and treadling lines (each "k=v" joined by ';'),
    /// white warp, blue weft.
    fn wif(
        shafts: usize,
        treadles: usize,
        threading: &[&str],
        tieup: &[&str],
        treadling: &[&str],
    ) -> String {
        format!(
            "[WIF]\nVersion=1.1\nDate=December 2, 2026\nDevelopers=weft tests\nSource Program=hand\n\
             [CONTENTS]\nCOLOR PALETTE=true\nWEAVING=true\nWARP=true\nWEFT=true\nTHREADING=true\nTIEUP=true\nTREADLING=true\nCOLOR TABLE=true\n\
             [COLOR PALETTE]\nEntries=2\nRange=0,255\n[COLOR TABLE]\n1=255,255,255\n2=0,0,255\n\
             [WEAVING]\nShafts={shafts}\nTreadles={treadles}\nRising Shed=true\n\
             [WARP]\nThreads={}\nColor=1\n[WEFT]\nThreads={}\nColor=2\n\
             [THREADING]\n{}\n[TIEUP]\n{}\n[TREADLING]\n{}\n",
            threading.len(),
            treadling.len(),
            threading.join("\n"),
            tieup.join("\n"),
            treadling.join("\n")
        )
    }

    /// "thread=shaft" lines of a straight draw over `shafts`, `n` threads.
    fn straight(shafts: usize, n: usize) -> Vec<String> {
        (1..=n)
            .map(|t| format!("{t}={}", (t - 1) % shafts + 1))
            .collect()
    }

    fn refs(v: &[String]) -> Vec<&str> {
        v.iter().map(String::as_str).collect()
    }

    fn rows(d: &Draft) -> Vec<String> {
        d.pattern.to_rows()
    }

    #[test]
    fn plain_weave_is_the_papers_plain() {
        let threading = straight(2, 12);
        let treadling: Vec<String> = (1..=10)
            .map(|p| format!("{p}={}", (p - 1) % 2 + 1))
            .collect();
        let d = Draft::parse(
            &wif(2, 2, &refs(&threading), &["1=1", "2=2"], &refs(&treadling)),
            "plain.wif",
        )
        .unwrap();
        // Pick 1 lifts shaft 1: thread 1 (column 0) is up, thread 2 down (weft on top).
        assert_eq!(rows(&d), ["|-", "-|"]);
        assert_eq!((d.threads, d.picks), (12, 10));
        // The paper's plain weave is the same interlacement shifted by one cell.
        let p = WeavePattern::plain();
        assert!(
            (0..2).all(|j| (0..2).all(|i| d.pattern.is_weft_up(i, j) == p.is_weft_up(i + 1, j)))
        );
        assert_eq!(d.mean_warp_colour(), Some([1.0, 1.0, 1.0]));
        assert_eq!(d.mean_weft_colour(), Some([0.0, 0.0, 1.0]));
    }

    #[test]
    fn twills_satin_and_basket_by_hand() {
        // 2/2 twill: straight draw on 4, tie-up 1=1,2 2=2,3 3=3,4 4=4,1, treadles 1..4.
        let th = straight(4, 16);
        let tr: Vec<String> = (1..=16)
            .map(|p| format!("{p}={}", (p - 1) % 4 + 1))
            .collect();
        let d = Draft::parse(
            &wif(
                4,
                4,
                &refs(&th),
                &["1=1,2", "2=2,3", "3=3,4", "4=4,1"],
                &refs(&tr),
            ),
            "twill22.wif",
        )
        .unwrap();
        assert_eq!(rows(&d), ["||--", "-||-", "--||", "|--|"]);

        // 3/1 twill (warp-faced): each treadle lifts three shafts.
        let d = Draft::parse(
            &wif(
                4,
                4,
                &refs(&th),
                &["1=1,2,3", "2=2,3,4", "3=3,4,1", "4=4,1,2"],
                &refs(&tr),
            ),
            "twill31.wif",
        )
        .unwrap();
        assert_eq!(rows(&d), ["|||-", "-|||", "|-||", "||-|"]);
        assert_eq!(d.pattern.weft_up_fraction(), 0.25);

        // 5-harness satin (move 2), warp-faced: treadle k lifts every shaft but 2k-1 (mod 5).
        let th5 = straight(5, 20);
        let tr5: Vec<String> = (1..=20)
            .map(|p| format!("{p}={}", (p - 1) % 5 + 1))
            .collect();
        let tie5: Vec<String> = (1..=5)
            .map(|k| {
                let down = (2 * (k - 1)) % 5 + 1;
                let up: Vec<String> = (1..=5)
                    .filter(|s| *s != down)
                    .map(|s| s.to_string())
                    .collect();
                format!("{k}={}", up.join(","))
            })
            .collect();
        let d = Draft::parse(
            &wif(5, 5, &refs(&th5), &refs(&tie5), &refs(&tr5)),
            "satin.wif",
        )
        .unwrap();
        // Weft-up where i = 2j (mod 5): the crate's satin.
        assert_eq!(d.pattern, WeavePattern::satin());

        // 2/2 basket: threads in pairs on 2 shafts (1,1,2,2), picks in pairs.
        let thb: Vec<String> = (1..=16)
            .map(|t| format!("{t}={}", (t - 1) / 2 % 2 + 1))
            .collect();
        let trb: Vec<String> = (1..=8)
            .map(|p| format!("{p}={}", (p - 1) / 2 % 2 + 1))
            .collect();
        let d = Draft::parse(
            &wif(2, 2, &refs(&thb), &["1=1", "2=2"], &refs(&trb)),
            "basket.wif",
        )
        .unwrap();
        assert_eq!(rows(&d), ["||--", "||--", "--||", "--||"]);
    }

    #[test]
    fn a_liftplan_and_a_sinking_shed_give_the_same_cloth() {
        let th = straight(4, 8);
        let tr: Vec<String> = (1..=8)
            .map(|p| format!("{p}={}", (p - 1) % 4 + 1))
            .collect();
        let rising = Draft::parse(
            &wif(
                4,
                4,
                &refs(&th),
                &["1=1,2", "2=2,3", "3=3,4", "4=4,1"],
                &refs(&tr),
            ),
            "rising.wif",
        )
        .unwrap();
        // The same cloth as a liftplan.
        let lift = wif(4, 4, &refs(&th), &[], &[]).replace(
            "[TIEUP]\n\n[TREADLING]\n\n",
            "[LIFTPLAN]\n1=1,2\n2=2,3\n3=3,4\n4=4,1\n5=1,2\n6=2,3\n7=3,4\n8=4,1\n",
        );
        let lift = lift.replace("[WEFT]\nThreads=0", "[WEFT]\nThreads=8");
        assert_eq!(
            Draft::parse(&lift, "lift.wif").unwrap().pattern,
            rising.pattern
        );
        // A sinking-shed tie-up names the shafts that go down: the complement.
        let sinking = wif(
            4,
            4,
            &refs(&th),
            &["1=3,4", "2=4,1", "3=1,2", "4=2,3"],
            &refs(&tr),
        )
        .replace("Rising Shed=true", "Rising Shed=false");
        assert_eq!(
            Draft::parse(&sinking, "sink.wif").unwrap().pattern,
            rising.pattern
        );
    }

    #[test]
    fn stripes_give_per_thread_colours_and_their_mean() {
        // A tartan-like sett on a plain weave: warp 4 white, 2 blue; weft the same.
        let th = straight(2, 12);
        let tr: Vec<String> = (1..=12)
            .map(|p| format!("{p}={}", (p - 1) % 2 + 1))
            .collect();
        let mut text = wif(2, 2, &refs(&th), &["1=1", "2=2"], &refs(&tr));
        let stripes = |n: usize| -> String {
            (1..=n)
                .map(|t| format!("{t}={}", if (t - 1) % 6 < 4 { 1 } else { 2 }))
                .collect::<Vec<_>>()
                .join("\n")
        };
        text.push_str(&format!(
            "[WARP COLORS]\n{}\n[WEFT COLORS]\n{}\n",
            stripes(12),
            stripes(12)
        ));
        let d = Draft::parse(&text, "tartan.wif").unwrap();
        assert_eq!(d.colour_count(true), 2);
        assert_eq!(d.warp_colours[4], [0.0, 0.0, 1.0]);
        assert_eq!(d.warp_colours[0], [1.0, 1.0, 1.0]);
        let m = d.mean_warp_colour().unwrap();
        assert!(
            (m[0] - 4.0 / 6.0).abs() < 1e-6 && (m[2] - 1.0).abs() < 1e-6,
            "{m:?}"
        );
    }

    #[test]
    fn broken_drafts_are_errors_that_say_where() {
        let th = straight(2, 4);
        let tr = ["1=1", "2=2"];
        let good = wif(2, 2, &refs(&th), &["1=1", "2=2"], &tr);
        assert!(Draft::parse(&good, "g.wif").is_ok());
        let cases: Vec<(String, &str)> = vec![
            (good.replace("[WIF]", "[DRAFT]"), "no [WIF] section"),
            (good.replace("[WIF]\n", ""), "comes before any [SECTION]"),
            (good.replace("3=1\n", "3=7\n"), "[THREADING] line"),
            (good.replace("3=1\n", "3=7\n"), "shaft 7 is out of range"),
            (
                good.replace("[TREADLING]\n1=1", "[TREADLING]\n1=9"),
                "treadle 9 is out of range",
            ),
            (
                good.replace("[TREADLING]\n1=1", "[TREADLING]\n5=1"),
                "pick 5 is out of range",
            ),
            (
                good.replace("[WARP]\nThreads=4\nColor=1", "[WARP]\nThreads=4\nColor=3"),
                "colour 3 is not in the [COLOR TABLE]",
            ),
            (good.replace("Shafts=2\n", ""), "has no 'shafts='"),
            (
                good.replace("[TIEUP]", "[NOTIEUP]"),
                "neither a [LIFTPLAN] nor a [TIEUP]",
            ),
            (
                good.replace("2=0,0,255", "2=0,0,300"),
                "outside the palette's range",
            ),
            (good.replace("[THREADING]", "[THREADIN"), "no closing ']'"),
            (
                good.replace("4=2\n", "4=two\n"),
                "'two' is not a shaft number",
            ),
        ];
        for (text, needle) in cases {
            let e = Draft::parse(&text, "bad.wif").unwrap_err().to_string();
            assert!(e.contains(needle) && e.contains("bad.wif"), "{needle}: {e}");
        }
    }

    #[test]
    fn a_repeat_past_eight_cells_is_refused_with_its_size() {
        // A 10-shaft straight twill: the interlacement repeats every 10 x 10.
        let th = straight(10, 20);
        let tr: Vec<String> = (1..=20)
            .map(|p| format!("{p}={}", (p - 1) % 10 + 1))
            .collect();
        let tie: Vec<String> = (1..=10).map(|k| format!("{k}={k}")).collect();
        let e = Draft::parse(&wif(10, 10, &refs(&th), &refs(&tie), &refs(&tr)), "big.wif")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("repeats every 10 warp threads x 10 picks") && e.contains("8 x 8"),
            "{e}"
        );
    }
}
