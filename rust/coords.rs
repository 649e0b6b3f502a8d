//! Rusinkiewicz's half/difference parameterisation of direction pairs.
//!
//! H = normalize(ω_i + ω_o) has spherical angles (θ_h, φ_h); D is ω_i expressed in the
//! frame that rotates H to the pole, with angles (θ_d, φ_d). All angles are computed
//! with `atan2`, never `acos`, so they keep full precision at the poles. Azimuths lie in
//! (−π, π].

use rayon::prelude::*;

use crate::error::{invalid_argument, Result};
use crate::parallel;

pub type Vec3 = [f64; 3];

/// (θ_h, φ_h, θ_d, φ_d).
pub type Rusinkiewicz = [f64; 4];

#[inline]
fn norm(v: Vec3) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// `v / |v|`, scaled first by its largest component so that tiny or huge vectors
/// neither underflow nor overflow.
#[inline]
pub(crate) fn normalize(v: Vec3) -> Vec3 {
    let largest = v[0].abs().max(v[1].abs()).max(v[2].abs());
    let u = [v[0] / largest, v[1] / largest, v[2] / largest];
    let length = norm(u);
    [u[0] / length, u[1] / length, u[2] / length]
}

#[inline]
fn unit_from_angles(theta: f64, phi: f64) -> Vec3 {
    let (sin_t, cos_t) = theta.sin_cos();
    let (sin_p, cos_p) = phi.sin_cos();
    [sin_t * cos_p, sin_t * sin_p, cos_t]
}

#[inline]
fn angles_of_unit(v: Vec3) -> (f64, f64) {
    (v[0].hypot(v[1]).atan2(v[2]), v[1].atan2(v[0]))
}

/// The rotation that takes the pole to `h`, as (cos θ, sin θ, cos φ, sin φ) of h.
#[inline]
fn frame_of(h: Vec3) -> [f64; 4] {
    let rho = h[0].hypot(h[1]);
    if rho == 0.0 {
        [h[2].signum(), 0.0, 1.0, 0.0]
    } else {
        [h[2], rho, h[0] / rho, h[1] / rho]
    }
}

/// Rotates `v` from the frame of `h` to the world: R_z(φ) R_y(θ) v.
#[inline]
fn to_world([cos_t, sin_t, cos_p, sin_p]: [f64; 4], v: Vec3) -> Vec3 {
    let x = cos_t * v[0] + sin_t * v[2];
    let z = -sin_t * v[0] + cos_t * v[2];
    [cos_p * x - sin_p * v[1], sin_p * x + cos_p * v[1], z]
}

/// Rotates `v` from the world into the frame of `h`: R_y(−θ) R_z(−φ) v.
#[inline]
fn to_local([cos_t, sin_t, cos_p, sin_p]: [f64; 4], v: Vec3) -> Vec3 {
    let x = cos_p * v[0] + sin_p * v[1];
    let y = -sin_p * v[0] + cos_p * v[1];
    [cos_t * x - sin_t * v[2], y, sin_t * x + cos_t * v[2]]
}

/// Half and difference vectors of a direction pair (inputs need not be normalised).
/// Where ω_i = −ω_o the half vector is undefined; we take the pole, the limit of two
/// directions approaching opposite grazing angles.
#[inline]
pub fn half_diff(wi: Vec3, wo: Vec3) -> (Vec3, Vec3) {
    let (wi, wo) = (normalize(wi), normalize(wo));
    let sum = [wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]];
    let h = if norm(sum) > 1e-12 {
        normalize(sum)
    } else {
        [0.0, 0.0, 1.0]
    };
    (h, to_local(frame_of(h), wi))
}

/// (ω_i, ω_o) → (θ_h, φ_h, θ_d, φ_d).
#[inline]
pub fn to_rusinkiewicz(wi: Vec3, wo: Vec3) -> Rusinkiewicz {
    let (h, d) = half_diff(wi, wo);
    let (theta_h, phi_h) = angles_of_unit(h);
    let (theta_d, phi_d) = angles_of_unit(d);
    [theta_h, phi_h, theta_d, phi_d]
}

/// (θ_h, φ_h, θ_d, φ_d) → unit (ω_i, ω_o). ω_o is D mirrored about the pole of the
/// half-vector frame, so ω_i and ω_o swap under φ_d → φ_d + π.
#[inline]
pub fn from_rusinkiewicz([theta_h, phi_h, theta_d, phi_d]: Rusinkiewicz) -> (Vec3, Vec3) {
    let frame = frame_of(unit_from_angles(theta_h, phi_h));
    let d = unit_from_angles(theta_d, phi_d);
    (to_world(frame, d), to_world(frame, [-d[0], -d[1], d[2]]))
}

/// The NBRDF input: H and D as Cartesian vectors for (θ_h, φ_h, θ_d, φ_d).
#[inline]
pub fn half_diff_of_angles([theta_h, phi_h, theta_d, phi_d]: Rusinkiewicz) -> (Vec3, Vec3) {
    (unit_from_angles(theta_h, phi_h), unit_from_angles(theta_d, phi_d))
}

// ---------------------------------------------------------------------------------------
// Batched forms: rows in, rows out, in parallel.

/// Checks that every direction is finite and non-zero; names the first bad row.
pub fn validate_directions(name: &str, directions: &[Vec3]) -> Result<()> {
    let bad = |v: &Vec3| {
        let largest = v[0].abs().max(v[1].abs()).max(v[2].abs());
        !(largest > 0.0 && v.iter().all(|x| x.is_finite()))
    };
    match parallel::position_first(directions, bad) {
        Some(row) => invalid_argument!(
            "{name} row {row} is not a finite non-zero vector: {:?}",
            directions[row]
        ),
        None => Ok(()),
    }
}

pub fn validate_angles(name: &str, angles: &[Rusinkiewicz]) -> Result<()> {
    match parallel::position_first(angles, |a| a.iter().any(|x| !x.is_finite())) {
        Some(row) => invalid_argument!("{name} row {row} is not finite: {:?}", angles[row]),
        None => Ok(()),
    }
}

fn check_same_length(wi: &[Vec3], wo: &[Vec3]) -> Result<()> {
    if wi.len() != wo.len() {
        return invalid_argument!("wi has {} rows but wo has {}", wi.len(), wo.len());
    }
    validate_directions("wi", wi)?;
    validate_directions("wo", wo)
}

pub fn batch_to_rusinkiewicz(wi: &[Vec3], wo: &[Vec3]) -> Result<Vec<Rusinkiewicz>> {
    check_same_length(wi, wo)?;
    Ok(wi
        .par_iter()
        .zip(wo)
        .with_min_len(4096)
        .map(|(&a, &b)| to_rusinkiewicz(a, b))
        .collect())
}

pub fn batch_half_diff(wi: &[Vec3], wo: &[Vec3]) -> Result<(Vec<Vec3>, Vec<Vec3>)> {
    check_same_length(wi, wo)?;
    Ok(wi
        .par_iter()
        .zip(wo)
        .with_min_len(4096)
        .map(|(&a, &b)| half_diff(a, b))
        .unzip())
}

pub fn batch_from_rusinkiewicz(angles: &[Rusinkiewicz]) -> Result<(Vec<Vec3>, Vec<Vec3>)> {
    validate_angles("angles", angles)?;
    Ok(angles
        .par_iter()
        .with_min_len(4096)
        .map(|&a| from_rusinkiewicz(a))
        .unzip())
}

pub fn batch_half_diff_of_angles(angles: &[Rusinkiewicz]) -> Result<(Vec<Vec3>, Vec<Vec3>)> {
    validate_angles("angles", angles)?;
    Ok(angles
        .par_iter()
        .with_min_len(4096)
        .map(|&a| half_diff_of_angles(a))
        .unzip())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3, tolerance: f64) -> bool {
        (0..3).all(|i| (a[i] - b[i]).abs() <= tolerance)
    }

    #[test]
    fn specular_pair_has_zero_half_angle() {
        let wi = unit_from_angles(0.7, 0.3);
        let wo = [-wi[0], -wi[1], wi[2]];
        let [theta_h, _, theta_d, _] = to_rusinkiewicz(wi, wo);
        assert!(theta_h.abs() < 1e-15);
        assert!((theta_d - 0.7).abs() < 1e-14);
    }

    #[test]
    fn round_trip_directions() {
        for i in 0..50 {
            let wi = unit_from_angles(0.03 * i as f64, 0.4 * i as f64);
            let wo = unit_from_angles(1.5 - 0.02 * i as f64, -0.1 * i as f64);
            let (wi2, wo2) = from_rusinkiewicz(to_rusinkiewicz(wi, wo));
            assert!(close(wi, wi2, 1e-13) && close(wo, wo2, 1e-13), "{i}");
        }
    }

    #[test]
    fn opposite_directions_do_not_give_nan() {
        let angles = to_rusinkiewicz([1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]);
        assert!(angles.iter().all(|x| x.is_finite()));
    }
}
