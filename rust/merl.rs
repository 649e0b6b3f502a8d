//! The MERL isotropic BRDF binary format (Matusik et al. 2003).
//!
//! A file is three little-endian `i32` dimensions `(90, 90, 180)` = (θ_h, θ_d, φ_d bins)
//! followed by `3 × 1,458,000` little-endian `f64`, channel-major (all red, then green,
//! then blue). Physical reflectance is the stored value times a per-channel scale.
//! Negative values mark missing measurements and are kept exactly as stored.

use std::f64::consts::{FRAC_PI_2, PI};
use std::fs::File;
use std::io::{ErrorKind, Read, Write};
use std::os::unix::fs::FileExt;
use std::path::Path;

use rayon::prelude::*;

use crate::coords::{self, Vec3};
use crate::error::{invalid_argument, Error, Result};
use crate::parallel;

pub const N_THETA_H: usize = 90;
pub const N_THETA_D: usize = 90;
pub const N_PHI_D: usize = 180;
/// Bins per channel.
pub const N_BINS: usize = N_THETA_H * N_THETA_D * N_PHI_D;
/// Values in a whole table (three channels).
pub const N_VALUES: usize = 3 * N_BINS;
const HEADER_BYTES: usize = 12;
/// Size of every valid MERL file: 34,992,012 bytes.
pub const FILE_BYTES: usize = HEADER_BYTES + 8 * N_VALUES;
/// Stored value × scale = reflectance, per channel (MERL's reference reader).
pub const CHANNEL_SCALES: [f64; 3] = [1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0];
/// What lookups return where no measurement is available.
pub const MISSING: f64 = -1.0;

/// Flat index of a bin inside one channel.
#[inline]
pub fn flat_index(theta_h: usize, theta_d: usize, phi_d: usize) -> usize {
    phi_d + N_PHI_D * (theta_d + N_THETA_D * theta_h)
}

// ---------------------------------------------------------------------------------------
// Reading and writing

/// Reads a MERL file. With `physical_units` the channel scales are applied; without,
/// the values are returned exactly as stored.
pub fn read_merl(path: &Path, physical_units: bool) -> Result<Vec<f64>> {
    let mut file = File::open(path).map_err(|e| Error::io(path, e))?;
    let metadata = file.metadata().map_err(|e| Error::io(path, e))?;
    if metadata.is_dir() {
        return Err(Error::io(path, std::io::Error::from(ErrorKind::IsADirectory)));
    }

    // Validate the header before allocating anything of the size it claims.
    let mut header = [0u8; HEADER_BYTES];
    file.read_exact(&mut header).map_err(|e| match e.kind() {
        ErrorKind::UnexpectedEof => Error::merl_format(
            path,
            format!("file is {} bytes, too short for the 12-byte header", metadata.len()),
        ),
        _ => Error::io(path, e),
    })?;
    let dims: [i32; 3] = std::array::from_fn(|i| i32::from_le_bytes(header[4 * i..4 * i + 4].try_into().unwrap()));
    if dims != [N_THETA_H as i32, N_THETA_D as i32, N_PHI_D as i32] {
        return Err(Error::merl_format(
            path,
            format!(
                "header dimensions are {} × {} × {}; a MERL file has 90 × 90 × 180",
                dims[0], dims[1], dims[2]
            ),
        ));
    }
    if metadata.len() != FILE_BYTES as u64 {
        return Err(Error::merl_format(
            path,
            format!(
                "file is {} bytes but a 90 × 90 × 180 MERL file is {FILE_BYTES} bytes{}",
                metadata.len(),
                if (metadata.len() as usize) < FILE_BYTES {
                    " (truncated?)"
                } else {
                    ""
                }
            ),
        ));
    }

    let mut values = vec![0f64; N_VALUES];
    let all_finite = read_values(&file, &mut values, physical_units).map_err(|e| match e.kind() {
        ErrorKind::UnexpectedEof => Error::merl_format(path, "file shrank while being read"),
        _ => Error::io(path, e),
    })?;
    if !all_finite {
        let position = parallel::position_first(&values, |v| !v.is_finite()).expect("a non-finite value was seen");
        return Err(Error::merl_format(
            path,
            format!(
                "value {} at byte offset {} ({}) is not finite",
                values[position],
                HEADER_BYTES + 8 * position,
                describe_position(position)
            ),
        ));
    }
    Ok(values)
}

/// Values per parallel read: big enough for efficient I/O, small enough to stay in cache
/// while they are checked and scaled.
const READ_CHUNK: usize = 1 << 17;

/// Reads the values straight into `values` (no intermediate byte buffer) in parallel
/// chunks, checking and scaling each chunk while it is in cache. Returns whether every
/// value was finite.
fn read_values(file: &File, values: &mut [f64], physical_units: bool) -> std::io::Result<bool> {
    let finite_chunks =
        values
            .par_chunks_mut(N_BINS)
            .zip(CHANNEL_SCALES)
            .enumerate()
            .map(|(channel, (values, scale))| {
                values
                    .par_chunks_mut(READ_CHUNK)
                    .enumerate()
                    .map(move |(index, chunk)| {
                        let offset = HEADER_BYTES + 8 * (channel * N_BINS + index * READ_CHUNK);
                        file.read_exact_at(bytemuck::cast_slice_mut(chunk), offset as u64)?;
                        if cfg!(target_endian = "big") {
                            chunk
                                .iter_mut()
                                .for_each(|v| *v = f64::from_bits(v.to_bits().swap_bytes()));
                        }
                        let finite = chunk.iter().all(|v| v.is_finite());
                        if physical_units {
                            chunk.iter_mut().for_each(|v| *v *= scale);
                        }
                        Ok(finite)
                    })
            });
    finite_chunks.flatten().try_reduce(|| true, |a, b| Ok(a && b))
}

/// Writes a MERL file atomically (a temporary file in the same folder, then a rename),
/// so a failure never leaves a half-written file at `path`.
///
/// With `physical_units`, each value is divided by its channel scale, choosing the stored
/// value whose product with the scale reproduces the input exactly when one exists. So
/// reading back returns the same array, and a file written by this function is
/// reproduced byte for byte by a read–write round trip.
pub fn write_merl(path: &Path, values: &[f64], physical_units: bool) -> Result<()> {
    if values.len() != N_VALUES {
        return Err(Error::merl_format(
            path,
            format!(
                "cannot write {} values; a MERL table holds 3 × 90 × 90 × 180 = {N_VALUES}",
                values.len()
            ),
        ));
    }
    if let Some(position) = parallel::position_first(values, |v| !v.is_finite()) {
        return Err(Error::merl_format(
            path,
            format!(
                "cannot write non-finite value {} at {}",
                values[position],
                describe_position(position)
            ),
        ));
    }
    if path.is_dir() {
        return Err(Error::io(path, std::io::Error::from(ErrorKind::IsADirectory)));
    }

    let mut stored = values.to_vec();
    if physical_units {
        for_each_channel(&mut stored, |scale, v| *v = stored_value(*v, scale));
    }
    let mut bytes = Vec::with_capacity(FILE_BYTES);
    for dim in [N_THETA_H, N_THETA_D, N_PHI_D] {
        bytes.extend_from_slice(&(dim as i32).to_le_bytes());
    }
    for v in &stored {
        bytes.extend_from_slice(&v.to_le_bytes());
    }

    let folder = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    };
    let mut temporary = tempfile::NamedTempFile::new_in(folder).map_err(|e| Error::io(path, e))?;
    temporary.write_all(&bytes).map_err(|e| Error::io(path, e))?;
    temporary.as_file().sync_all().map_err(|e| Error::io(path, e))?;
    temporary.persist(path).map_err(|e| Error::io(path, e.error))?;
    Ok(())
}

/// Applies `f(scale, value)` to every value, channel by channel, in parallel.
fn for_each_channel(values: &mut [f64], f: impl Fn(f64, &mut f64) + Sync) {
    values
        .par_chunks_mut(N_BINS)
        .zip(CHANNEL_SCALES)
        .for_each(|(channel, scale)| {
            channel
                .par_chunks_mut(1 << 16)
                .for_each(|chunk| chunk.iter_mut().for_each(|v| f(scale, v)))
        });
}

/// The stored value `s` with `s * scale == reflectance` exactly, if one exists (the one
/// nearest `reflectance / scale`); otherwise `reflectance / scale`.
///
/// Multiplying by a scale that is not a power of two maps some pairs of neighbouring
/// doubles onto one double, so this choice is canonical rather than always the original.
fn stored_value(reflectance: f64, scale: f64) -> f64 {
    let guess = reflectance / scale;
    if guess * scale == reflectance {
        return guess;
    }
    let (mut up, mut down) = (guess, guess);
    for _ in 0..4 {
        up = up.next_up();
        down = down.next_down();
        if up * scale == reflectance {
            return up;
        }
        if down * scale == reflectance {
            return down;
        }
    }
    guess
}

fn describe_position(position: usize) -> String {
    let (channel, bin) = (position / N_BINS, position % N_BINS);
    let (theta_h, rest) = (bin / (N_THETA_D * N_PHI_D), bin % (N_THETA_D * N_PHI_D));
    format!(
        "channel {}, bin (θ_h {}, θ_d {}, φ_d {})",
        ["red", "green", "blue"][channel],
        theta_h,
        rest / N_PHI_D,
        rest % N_PHI_D
    )
}

// ---------------------------------------------------------------------------------------
// Bin index ↔ angle maps. Bin i sits at the angle whose continuous index is exactly i,
// as in MERL's reference code, which looks up bin floor(index).

/// θ_h of bin `i`: the θ_h axis is quadratic, θ_h = (i / 90)² · π/2.
pub fn theta_h_of_bin(i: f64) -> f64 {
    let t = i / N_THETA_H as f64;
    t * t * FRAC_PI_2
}
pub fn theta_d_of_bin(j: f64) -> f64 {
    j / N_THETA_D as f64 * FRAC_PI_2
}
pub fn phi_d_of_bin(k: f64) -> f64 {
    k / N_PHI_D as f64 * PI
}

/// Continuous bin coordinates of (θ_h, θ_d, φ_d): θ's clamped to [0, π/2], φ_d folded
/// into [0, π) by reciprocity. Integer parts give MERL's bins. Coordinates within 1e-9
/// of an integer snap to it, so the angle of bin i maps back to exactly i.
pub fn continuous_bin(theta_h: f64, theta_d: f64, phi_d: f64) -> [f64; 3] {
    let snap = |x: f64| if (x - x.round()).abs() < 1e-9 { x.round() } else { x };
    let h = snap((theta_h.clamp(0.0, FRAC_PI_2) / FRAC_PI_2).sqrt() * N_THETA_H as f64);
    let d = snap(theta_d.clamp(0.0, FRAC_PI_2) / FRAC_PI_2 * N_THETA_D as f64);
    let p = snap(phi_d.rem_euclid(PI) / PI * N_PHI_D as f64);
    [h, d, if p >= N_PHI_D as f64 { 0.0 } else { p }]
}

/// MERL's bin for (θ_h, θ_d, φ_d): floor of the continuous index, clamped.
pub fn bin_of_angles(theta_h: f64, theta_d: f64, phi_d: f64) -> [usize; 3] {
    let [h, d, p] = continuous_bin(theta_h, theta_d, phi_d);
    let floor = |x: f64, n: usize| (x.floor() as usize).min(n - 1);
    [floor(h, N_THETA_H), floor(d, N_THETA_D), floor(p, N_PHI_D)]
}

// ---------------------------------------------------------------------------------------
// Lookup at arbitrary angles

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lookup {
    /// The value of the nearest bin.
    Nearest,
    /// Trilinear in bin coordinates (θ_h on MERL's quadratic axis), periodic in φ_d,
    /// over the corners that hold a measurement.
    Trilinear,
}

/// Looks up `table` (`N_VALUES`, physical or stored units) at `(θ_h, θ_d, φ_d)` triples.
/// Returns RGB per query; negative (the table's own marker) where no measurement covers it.
pub fn lookup(table: &[f64], angles: &[[f64; 3]], method: Lookup) -> Result<Vec<[f64; 3]>> {
    if table.len() != N_VALUES {
        return invalid_argument!("table has {} values, expected 3 × 90 × 90 × 180", table.len());
    }
    if let Some(row) = parallel::position_first(angles, |a| a.iter().any(|x| !x.is_finite())) {
        return invalid_argument!("angles row {row} is not finite: {:?}", angles[row]);
    }
    Ok(angles
        .par_iter()
        .with_min_len(4096)
        .map(|&[h, d, p]| lookup_one(table, h, d, p, method))
        .collect())
}

/// Looks up `table` at direction pairs. Pairs with either direction below the horizon
/// return [`MISSING`], like bins MERL did not measure.
pub fn lookup_directions(table: &[f64], wi: &[Vec3], wo: &[Vec3], method: Lookup) -> Result<Vec<[f64; 3]>> {
    let angles = coords::batch_to_rusinkiewicz(wi, wo)?;
    let angles: Vec<[f64; 3]> = angles
        .iter()
        .map(|&[theta_h, _, theta_d, phi_d]| [theta_h, theta_d, phi_d])
        .collect();
    let mut rgb = lookup(table, &angles, method)?;
    rgb.par_iter_mut()
        .zip(wi.par_iter().zip(wo))
        .for_each(|(value, (i, o))| {
            if i[2] < 0.0 || o[2] < 0.0 {
                *value = [MISSING; 3];
            }
        });
    Ok(rgb)
}

pub(crate) fn lookup_one(table: &[f64], theta_h: f64, theta_d: f64, phi_d: f64, method: Lookup) -> [f64; 3] {
    let [h, d, p] = continuous_bin(theta_h, theta_d, phi_d);
    match method {
        Lookup::Nearest => nearest_bin_values(table, [h, d, p]),
        Lookup::Trilinear => {
            // (lower bin, upper bin, weight of upper) along each axis.
            let clamped = |x: f64, n: usize| {
                let x = x.min((n - 1) as f64);
                let lo = x.floor() as usize;
                (lo, (lo + 1).min(n - 1), x - lo as f64)
            };
            let (h0, h1, fh) = clamped(h, N_THETA_H);
            let (d0, d1, fd) = clamped(d, N_THETA_D);
            let p0 = p.floor() as usize % N_PHI_D;
            let (p1, fp) = ((p0 + 1) % N_PHI_D, p - p.floor());

            let mut sum = [0.0; 3];
            let mut weight_sum = [0.0; 3];
            for (hi, wh) in [(h0, 1.0 - fh), (h1, fh)] {
                for (di, wd) in [(d0, 1.0 - fd), (d1, fd)] {
                    for (pi, wp) in [(p0, 1.0 - fp), (p1, fp)] {
                        let weight = wh * wd * wp;
                        let bin = flat_index(hi, di, pi);
                        for c in 0..3 {
                            let value = table[c * N_BINS + bin];
                            if value >= 0.0 {
                                sum[c] += weight * value;
                                weight_sum[c] += weight;
                            }
                        }
                    }
                }
            }
            // Where no corner was measured, report the nearest bin's own (negative) marker.
            let nearest = nearest_bin_values(table, [h, d, p]);
            std::array::from_fn(|c| {
                if weight_sum[c] > 0.0 {
                    sum[c] / weight_sum[c]
                } else {
                    nearest[c]
                }
            })
        }
    }
}

fn nearest_bin_values(table: &[f64], [h, d, p]: [f64; 3]) -> [f64; 3] {
    let bin = flat_index(
        (h.round() as usize).min(N_THETA_H - 1),
        (d.round() as usize).min(N_THETA_D - 1),
        p.round() as usize % N_PHI_D,
    );
    std::array::from_fn(|c| table[c * N_BINS + bin])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bin_angle_maps_round_trip() {
        for i in 0..N_THETA_H {
            for j in 0..N_THETA_D {
                let k = (i * 7 + j) % N_PHI_D;
                let bin = bin_of_angles(
                    theta_h_of_bin(i as f64),
                    theta_d_of_bin(j as f64),
                    phi_d_of_bin(k as f64),
                );
                assert_eq!(bin, [i, j, k]);
            }
        }
    }

    #[test]
    fn stored_value_inverts_the_scale() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..100_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let stored = f64::from_bits(state >> 2) % 1e6;
            for scale in CHANNEL_SCALES {
                let reflectance = stored * scale;
                assert_eq!(stored_value(reflectance, scale) * scale, reflectance);
            }
        }
    }

    #[test]
    fn trilinear_equals_nearest_at_bin_positions() {
        let table: Vec<f64> = (0..N_VALUES).map(|i| (i % 977) as f64).collect();
        let angles = [theta_h_of_bin(30.0), theta_d_of_bin(45.0), phi_d_of_bin(100.0)];
        let nearest = lookup_one(&table, angles[0], angles[1], angles[2], Lookup::Nearest);
        let trilinear = lookup_one(&table, angles[0], angles[1], angles[2], Lookup::Trilinear);
        for c in 0..3 {
            assert!((nearest[c] - trilinear[c]).abs() < 1e-9 * nearest[c].abs().max(1.0));
            assert_eq!(nearest[c], table[c * N_BINS + flat_index(30, 45, 100)]);
        }
    }
}
