//! What each descriptor binding holds: the comment at its GLSL declaration, read from the shader's
//! source and its `#include`s.

use super::INCLUDES;
use crate::vk::Shader;

/// The prose of set `set` binding `binding` of `shader`: the comment that ends the line of its
/// declaration (`layout(set = S, binding = B ...) ...;  // prose`) in the shader's GLSL or one of
/// its `#include`s, the one place a binding is described (Sascha Willems' samples comment every
/// binding where it is declared). None when the declaration has no comment or is not found.
pub fn binding_comment(shader: &Shader, set: u32, binding: u32) -> Option<String> {
    fn search(source: &str, set: u32, binding: u32, seen: &mut Vec<String>) -> Option<String> {
        let lines: Vec<&str> = source.lines().collect();
        for (i, line) in lines.iter().enumerate() {
            let code = line.trim_start();
            if let Some(name) = code
                .strip_prefix("#include \"")
                .and_then(|r| r.strip_suffix('"'))
            {
                if seen.iter().any(|s| s == name) {
                    continue;
                }
                seen.push(name.to_string());
                let found = INCLUDES
                    .iter()
                    .find(|(n, _)| *n == name)
                    .and_then(|(_, text)| search(text, set, binding, seen));
                if found.is_some() {
                    return found;
                }
                continue;
            }
            if code.starts_with("//") || !declares(code, set, binding) {
                continue;
            }
            // The declaration runs to the ';' outside its braces (a block may span lines); its
            // prose is the first comment on those lines (after the declaration on one line, on
            // the member line or the closing line of a block).
            let mut depth = 0i32;
            let mut prose = None;
            for line in &lines[i..] {
                let (code, comment) = match line.split_once("//") {
                    Some((code, comment)) => (code, comment.trim()),
                    None => (*line, ""),
                };
                if prose.is_none() && !comment.is_empty() {
                    prose = Some(comment.to_string());
                }
                let mut ended = false;
                for c in code.chars() {
                    match c {
                        '{' => depth += 1,
                        '}' => depth -= 1,
                        ';' if depth == 0 => ended = true,
                        _ => {}
                    }
                }
                if ended {
                    break;
                }
            }
            return prose;
        }
        None
    }
    search(shader.source, set, binding, &mut Vec::new())
}

/// Whether a GLSL line starts a `layout(...)` declaration with `set = S` and `binding = B`.
fn declares(code: &str, set: u32, binding: u32) -> bool {
    let Some(rest) = code.strip_prefix("layout") else {
        return false;
    };
    let Some(open) = rest.find('(') else {
        return false;
    };
    let Some(close) = rest.find(')') else {
        return false;
    };
    let qualifiers = &rest[open + 1..close];
    let value = |key: &str| {
        qualifiers.split(',').find_map(|q| {
            let (k, v) = q.split_once('=')?;
            (k.trim() == key).then(|| v.trim().parse::<u32>().ok())?
        })
    };
    value("set") == Some(set) && value("binding") == Some(binding)
}
