//! Values from the command line and from files, parsed where they enter: what they refuse says
//! what was given and what to give instead. (The bottom layer: the environment, the renderer and
//! the binary all parse with these.)

use crate::Error;

/// Parses `X,Y,Z`, e.g. `0,1.5,3.5`.
pub fn parse_vec3(what: &str, text: &str) -> crate::Result<glam::Vec3> {
    let bad = || {
        Error::input(format!(
            "{what} '{text}' is not three comma-separated numbers X,Y,Z (e.g. 0,1.5,3.5)"
        ))
    };
    let parts: Vec<f32> = text
        .split(',')
        .map(|p| p.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    match parts[..] {
        [x, y, z] if x.is_finite() && y.is_finite() && z.is_finite() => {
            Ok(glam::Vec3::new(x, y, z))
        }
        _ => Err(bad()),
    }
}

/// Parses a number flag (`--env-rotation 90`): NaN and infinities are refused here, where the
/// value enters, whatever later uses it (an environment, the default key light, a camera).
pub fn parse_finite(what: &str, text: &str) -> crate::Result<f32> {
    match text.trim().parse::<f32>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(Error::input(format!(
            "{what} {text} is not a finite number: give an ordinary number (NaN and infinities have no meaning here)"
        ))),
        Err(_) => Err(Error::input(format!("{what} '{text}' is not a number"))),
    }
}
