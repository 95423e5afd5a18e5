//! The viewer's orbit camera: a target, a distance, yaw and pitch (Y up).

use glam::{Mat4, Vec3};

use crate::scene::{Camera, Scene};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    pub target: Vec3,
    pub distance: f32,
    /// Radians about +Y; 0 looks down -Z.
    pub yaw: f32,
    /// Radians above the horizon, within ±89°.
    pub pitch: f32,
    /// Vertical field of view, radians.
    pub yfov: f32,
}

const MAX_PITCH: f32 = 89.0 * std::f32::consts::PI / 180.0;

impl Orbit {
    /// The orbit that sees what `camera` sees: the same eye and direction, the target where the
    /// view ray passes closest to the centre of the scene's bounds.
    pub fn from_camera(camera: &Camera, scene: &Scene) -> Orbit {
        let inv = camera.view.inverse();
        let eye = inv.w_axis.truncate();
        let forward = (-inv.z_axis.truncate()).normalize_or(Vec3::NEG_Z);
        let center = scene
            .bounds()
            .map(|b| (b.min + b.max) * 0.5)
            .unwrap_or(Vec3::ZERO);
        let distance = (center - eye).dot(forward).max(1e-3);
        Orbit {
            target: eye + forward * distance,
            distance,
            yaw: (-forward.x).atan2(-forward.z),
            pitch: (-forward.y).asin().clamp(-MAX_PITCH, MAX_PITCH),
            yfov: camera.yfov,
        }
    }

    /// The orbit that frames the scene (the bounding sphere of what casts shadows, so that a
    /// staged ground that only receives does not shrink the subject; all of it when nothing
    /// casts) from the current direction.
    pub fn framed(&self, scene: &Scene) -> Orbit {
        let Some(b) = scene.caster_bounds().or_else(|| scene.bounds()) else {
            return *self;
        };
        let radius = ((b.max - b.min).length() * 0.5).max(1e-3);
        let half = (self.yfov * 0.5).clamp(0.05, 1.5);
        Orbit {
            target: (b.min + b.max) * 0.5,
            distance: radius / half.sin() * 1.05,
            ..*self
        }
    }

    /// Unit vector from the target to the eye.
    pub fn back(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        Vec3::new(sy * cp, sp, cy * cp)
    }

    pub fn eye(&self) -> Vec3 {
        self.target + self.back() * self.distance
    }

    /// Turns by a drag of (dx, dy) pixels in a window `height` pixels high.
    pub fn rotate(&mut self, dx: f32, dy: f32, height: f32) {
        let k = std::f32::consts::PI / height.max(1.0);
        self.yaw -= dx * k;
        self.pitch = (self.pitch + dy * k).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Moves the target in the view plane so the point under the cursor follows it.
    pub fn pan(&mut self, dx: f32, dy: f32, height: f32) {
        let back = self.back();
        let right = Vec3::Y.cross(back).normalize_or(Vec3::X);
        let up = back.cross(right);
        let per_pixel = 2.0 * self.distance * (self.yfov * 0.5).tan() / height.max(1.0);
        self.target += (-right * dx + up * dy) * per_pixel;
    }

    /// Wheel steps: positive comes closer.
    pub fn zoom(&mut self, steps: f32) {
        self.distance = (self.distance * 0.9f32.powf(steps)).clamp(1e-4, 1e7);
    }

    /// The camera for the renderer (near and far planes fitted to the scene as for --eye).
    pub fn camera(&self, scene: &Scene) -> crate::Result<Camera> {
        scene.look_at_camera(self.eye(), self.target, self.yfov)
    }

    /// World-to-view matrix (for tests).
    pub fn view(&self) -> Mat4 {
        Mat4::look_at_rh(self.eye(), self.target, Vec3::Y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn from_camera_round_trips_eye_and_direction() {
        let scene = crate::scene::default_scene();
        let cam = scene.camera(None).unwrap();
        let orbit = Orbit::from_camera(&cam, &scene);
        let inv = cam.view.inverse();
        let eye = inv.w_axis.truncate();
        // 1e-3 of the distance: f32 trigonometry on a unit vector and a product with the distance.
        assert!(
            (orbit.eye() - eye).length() < 1e-3 * orbit.distance.max(1.0),
            "{} vs {eye}",
            orbit.eye()
        );
        let forward = -inv.z_axis.truncate().normalize();
        assert!((-orbit.back()).dot(forward) > 0.99999);
    }
}
