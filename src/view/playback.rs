//! Playing the scene's glTF animations in the window: which animation, playing or paused, the
//! time (looping over the animation's duration), and whether the scene needs posing again.

use crate::scene::Scene;

/// The viewer's animation clock.
#[derive(Clone, Debug, PartialEq)]
pub struct Playback {
    /// Index into [`Scene::animations`].
    pub index: usize,
    pub playing: bool,
    /// Seconds into the animation, in [0, duration].
    pub time: f32,
    /// What the scene was last posed at (None: not yet).
    posed: Option<(usize, f32)>,
}

impl Playback {
    /// The clock for `scene`: None without animations. `animation` (a name or index, as for
    /// `--animation`) picks one, else the first; `time` starts it paused there, else it plays
    /// from 0, as glTF viewers do.
    pub fn for_scene(
        scene: &Scene,
        animation: Option<&str>,
        time: Option<f32>,
    ) -> crate::Result<Option<Playback>> {
        if scene.animations().is_empty() {
            if animation.is_some() || time.is_some() {
                return Err(crate::Error::input(format!(
                    "{} has no animations, so --animation and --time do not apply; leave them out",
                    scene.source
                )));
            }
            return Ok(None);
        }
        let index = match animation {
            Some(a) => scene.find_animation(a)?,
            None => 0,
        };
        if let Some(t) = time {
            if !t.is_finite() || t < 0.0 {
                return Err(crate::Error::input(format!(
                    "--time {t} is not a time in the animation: give seconds, 0 or more"
                )));
            }
        }
        Ok(Some(Playback {
            index,
            playing: time.is_none(),
            time: time.unwrap_or(0.0),
            posed: None,
        }))
    }

    /// Moves the clock on by `dt` seconds when playing, looping over `duration` (an animation
    /// of one instant stays at 0).
    pub fn advance(&mut self, dt: f32, duration: f32) {
        if !self.playing || dt.is_nan() || dt <= 0.0 {
            return;
        }
        self.time = if duration > 0.0 {
            (self.time + dt).rem_euclid(duration)
        } else {
            0.0
        };
    }

    /// Whether the scene's pose is not this clock's (a new animation or time).
    pub fn needs_pose(&self) -> bool {
        self.posed != Some((self.index, self.time))
    }

    /// Records that the scene is posed at this clock.
    pub fn posed(&mut self) {
        self.posed = Some((self.index, self.time));
    }

    /// Forgets the pose (the scene was loaded again): the next frame poses it.
    pub fn repose(&mut self) {
        self.posed = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clock(playing: bool) -> Playback {
        Playback {
            index: 0,
            playing,
            time: 0.0,
            posed: None,
        }
    }

    #[test]
    fn the_clock_loops_and_pauses() {
        let mut p = clock(true);
        p.advance(0.75, 1.0);
        assert_eq!(p.time, 0.75);
        p.advance(0.5, 1.0);
        assert!((p.time - 0.25).abs() < 1e-6, "{}", p.time);
        assert!(p.needs_pose());
        p.posed();
        assert!(!p.needs_pose());
        p.playing = false;
        p.advance(0.5, 1.0);
        assert!((p.time - 0.25).abs() < 1e-6, "paused");
        assert!(!p.needs_pose(), "paused: posed once");
        p.playing = true;
        p.advance(f32::NAN, 1.0);
        p.advance(3.0, 0.0);
        assert_eq!(p.time, 0.0, "an animation of one instant");
    }
}
