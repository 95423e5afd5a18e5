//! `weft cache`: what weft's cache on disk holds (src/cache.rs), and emptying it.

use super::*;

#[derive(Args)]
pub(super) struct CacheArgs {
    /// Remove every entry of weft's cache (only weft's own files: the directory may be shared).
    #[arg(long)]
    clear: bool,
}

fn size(bytes: u64) -> String {
    match bytes {
        b if b >= 1 << 30 => format!("{:.2} GiB", b as f64 / (1u64 << 30) as f64),
        b if b >= 1 << 20 => format!("{:.1} MiB", b as f64 / (1u64 << 20) as f64),
        b if b >= 1 << 10 => format!("{:.1} KiB", b as f64 / (1u64 << 10) as f64),
        b => format!("{b} B"),
    }
}

pub(super) fn run(args: CacheArgs) -> anyhow::Result<()> {
    let text = report(args);
    // A reader that stops early (`weft cache | head`) is not an error.
    match std::io::Write::write_all(&mut std::io::stdout().lock(), text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}

fn report(args: CacheArgs) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let Some(dir) = weft::cache::dir() else {
        return "weft's cache is off (WEFT_CACHE_DIR is \"off\" or empty, or there is no HOME): \
                every run computes its pipelines and environments afresh\n"
            .to_string();
    };
    if args.clear {
        let removed = weft::cache::clear_in(&dir);
        let bytes: u64 = removed.iter().map(|e| e.bytes).sum();
        return format!(
            "removed {} entries ({}) from {}\n",
            removed.len(),
            size(bytes),
            dir.display()
        );
    }
    let entries = weft::cache::entries_in(&dir);
    let _ = writeln!(out, "{}", dir.display());
    let _ = writeln!(
        out,
        "  (WEFT_CACHE_DIR, else $XDG_CACHE_HOME/weft or ~/.cache/weft; WEFT_CACHE_DIR=off turns it off)"
    );
    let _ = writeln!(
        out,
        "limit {} (WEFT_CACHE_MAX_SIZE: bytes or K/M/G); the least recently used entries go first",
        size(weft::cache::max_size())
    );
    let mut kinds: Vec<(&str, usize, u64)> = Vec::new();
    for e in &entries {
        match kinds.iter_mut().find(|k| k.0 == e.kind) {
            Some(k) => {
                k.1 += 1;
                k.2 += e.bytes;
            }
            None => kinds.push((&e.kind, 1, e.bytes)),
        }
    }
    kinds.sort();
    let _ = writeln!(out, "\n| kind | entries | size |\n|---|---|---|");
    for (kind, n, bytes) in &kinds {
        let _ = writeln!(out, "| {kind} | {n} | {} |", size(*bytes));
    }
    let total: u64 = entries.iter().map(|e| e.bytes).sum();
    let _ = writeln!(out, "| total | {} | {} |", entries.len(), size(total));
    out
}
