//! KHR_materials_iridescence's thin-film Fresnel (`iridescence_fresnel`, glsl/include/pbr.glsl,
//! and its Rust twin) against a ground truth that shares none of its approximations: the
//! reflectance of a dielectric film on a dielectric base computed spectrally in f64 — the
//! polarised Fresnel amplitudes of both interfaces (not Schlick), the exact Airy sum of every
//! order (not two), averaged over s and p — integrated over 380–780 nm against the CIE 1931
//! colour matching functions (Wyman, Sloan & Shirley's 2013 multi-lobe fit, not Belcour & Barla's
//! Fourier-space Gaussians) and taken to linear Rec. 709, each channel normalised so that a
//! spectrally flat reflectance R is (R, R, R) (the model's own convention: its mean term is
//! neutral).
//!
//! What the model gives up, and so what the bounds absorb: Schlick's curve for the interfaces
//! (the largest part, at grazing angles), the orders beyond two (small for films whose interfaces
//! reflect little), and the fits' own colour error. The test would fail on a wrong unit of
//! thickness (the fringes would move by a factor 10^3), a wrong phase (the colours of a film
//! denser than its base would swap for their complements), or a missing order.

use weft::reference::shading::iridescence_fresnel;

/// A piecewise Gaussian of the multi-lobe fit.
fn g(x: f64, mu: f64, s1: f64, s2: f64) -> f64 {
    let s = if x < mu { s1 } else { s2 };
    (-0.5 * ((x - mu) / s).powi(2)).exp()
}

/// CIE 1931 2° colour matching functions (Wyman, Sloan & Shirley 2013, their multi-lobe fit).
fn cmf(l: f64) -> [f64; 3] {
    [
        1.056 * g(l, 599.8, 37.9, 31.0) + 0.362 * g(l, 442.0, 16.0, 26.7)
            - 0.065 * g(l, 501.1, 20.4, 26.2),
        0.821 * g(l, 568.8, 46.9, 40.5) + 0.286 * g(l, 530.9, 16.3, 31.1),
        1.217 * g(l, 437.0, 11.8, 36.0) + 0.681 * g(l, 459.0, 26.0, 13.8),
    ]
}

/// Linear Rec. 709 channel sensitivities: the XYZ to Rec. 709 matrix applied to the matching
/// functions.
fn sensitivity(l: f64) -> [f64; 3] {
    let [x, y, z] = cmf(l);
    [
        3.2404542 * x - 1.5371385 * y - 0.4985314 * z,
        -0.9692660 * x + 1.8760108 * y + 0.0415560 * z,
        0.0556434 * x - 0.2040259 * y + 1.0572252 * z,
    ]
}

#[derive(Clone, Copy)]
struct C(f64, f64);
impl C {
    fn add(self, o: C) -> C {
        C(self.0 + o.0, self.1 + o.1)
    }
    fn mul(self, o: C) -> C {
        C(self.0 * o.0 - self.1 * o.1, self.0 * o.1 + self.1 * o.0)
    }
    fn div(self, o: C) -> C {
        let d = o.0 * o.0 + o.1 * o.1;
        C(
            (self.0 * o.0 + self.1 * o.1) / d,
            (self.1 * o.0 - self.0 * o.1) / d,
        )
    }
    fn norm2(self) -> f64 {
        self.0 * self.0 + self.1 * self.1
    }
}

/// The film's reflectance at wavelength `lambda` (nm): air (1) over a film of index n2 and
/// thickness d (nm) over a base of index n3, at cos θ1 = c, averaged over both polarisations.
fn airy(lambda: f64, c: f64, n2: f64, d: f64, n3: f64) -> f64 {
    let sin2 = 1.0 - c * c;
    let c2 = (1.0 - sin2 / (n2 * n2)).sqrt();
    let c3 = (1.0 - sin2 / (n3 * n3)).sqrt();
    let delta = 2.0 * std::f64::consts::PI / lambda * 2.0 * n2 * d * c2;
    let e = C(delta.cos(), delta.sin());
    let mut r = 0.0;
    for p in [false, true] {
        let (r12, r23) = if p {
            (
                (n2 * c - c2) / (n2 * c + c2),
                (n3 * c2 - n2 * c3) / (n3 * c2 + n2 * c3),
            )
        } else {
            (
                (c - n2 * c2) / (c + n2 * c2),
                (n2 * c2 - n3 * c3) / (n2 * c2 + n3 * c3),
            )
        };
        let num = C(r12, 0.0).add(C(r23, 0.0).mul(e));
        let den = C(1.0, 0.0).add(C(r12 * r23, 0.0).mul(e));
        r += 0.5 * num.div(den).norm2();
    }
    r
}

/// The film's colour: the spectral reflectance integrated against each channel's sensitivity,
/// normalised by the sensitivity's own integral.
fn truth(c: f64, n2: f64, d: f64, n3: f64) -> [f64; 3] {
    let mut sum = [0.0; 3];
    let mut norm = [0.0; 3];
    let mut l = 380.0;
    while l <= 780.0 {
        let s = sensitivity(l);
        let r = airy(l, c, n2, d, n3);
        for k in 0..3 {
            sum[k] += r * s[k];
            norm[k] += s[k];
        }
        l += 0.5;
    }
    [sum[0] / norm[0], sum[1] / norm[1], sum[2] / norm[2]]
}

fn f0_of(n: f64) -> f32 {
    (((n - 1.0) / (n + 1.0)).powi(2)) as f32
}

#[test]
fn the_flat_spectrum_is_white_and_no_film_is_the_base_fresnel() {
    // The normalisation: a film of the base's own index is no film, the base's Fresnel at every
    // wavelength, so each channel is that one number (normal incidence: F0 exactly).
    let t = truth(1.0, 1.5, 300.0, 1.5);
    for k in 0..3 {
        assert!((t[k] - 0.04).abs() < 1e-9, "channel {k}: {}", t[k]);
    }
    // And the model at thickness 0 and normal incidence is the base's F0, but for what the
    // specification's clamp of R12·R23 at 1e-5 leaves of the interference orders: √1e-5 ·
    // |R23 − 1| · 2|S|, 0.0073 here (bound 0.01). (Obliquely, thickness 0 is outside the model's
    // domain: see below.)
    let f = iridescence_fresnel(1.8, 1.0, 0.0, [0.04; 3]);
    for k in 0..3 {
        assert!((f[k] - 0.04).abs() < 0.01, "{f:?} against 0.04");
    }
}

#[test]
fn the_thin_film_fresnel_follows_the_spectral_airy_truth() {
    let films = [1.33, 1.5, 1.8, 2.4];
    let bases = [1.5, 2.0];
    let stats = |cosines: &[f64], thicknesses: &[f64], bases: &[f64]| {
        let (mut worst, mut sum, mut count) = (0.0f64, 0.0f64, 0usize);
        let mut worst_case = String::new();
        for &n2 in &films {
            for &n3 in bases {
                for &c in cosines {
                    for &d in thicknesses {
                        let t = truth(c, n2, d, n3);
                        let m = iridescence_fresnel(n2 as f32, c as f32, d as f32, [f0_of(n3); 3]);
                        for k in 0..3 {
                            let e = (m[k] as f64 - t[k]).abs();
                            sum += e;
                            count += 1;
                            if e > worst {
                                worst = e;
                                worst_case = format!(
                                    "film {n2} over {n3}, cos {c}, {d} nm: model {m:?}, truth {t:?}"
                                );
                            }
                        }
                    }
                }
            }
        }
        (sum / count as f64, worst, worst_case)
    };
    let films_nm: Vec<f64> = (2..=48).map(|i| i as f64 * 25.0).collect();
    let thin_nm: Vec<f64> = (0..=1).map(|i| i as f64 * 25.0).collect();
    for (label, cosines, mean_bound, worst_bound) in [
        ("near normal", &[1.0, 0.8][..], 0.01, 0.08),
        ("oblique", &[0.5, 0.35][..], 0.035, 0.2),
    ] {
        let (mean, worst, case) = stats(cosines, &films_nm, &bases);
        println!("{label}, 50-1200 nm: mean |error| {mean:.4}, worst {worst:.4} ({case})");
        assert!(mean < mean_bound, "{label}: mean error {mean}");
        assert!(worst < worst_bound, "{label}: worst error {worst}: {case}");
    }
    let (mean, worst, _) = stats(&[1.0, 0.8, 0.5, 0.35], &thin_nm, &bases);
    println!("0-25 nm, every angle (not bounded): mean {mean:.4}, worst {worst:.4}");
    let (mean, worst, _) = stats(&[1.0, 0.8, 0.5, 0.35], &films_nm, &[1.0]);
    println!("a free film, 50-1200 nm (not bounded): mean {mean:.4}, worst {worst:.4}");
}
