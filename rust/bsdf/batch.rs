//! The float32 evaluator: the steps of [`MeasuredBsdf::eval_pair`] on [`LANES`] pairs at a
//! time, in structure-of-arrays form so that the arithmetic vectorises across pairs.
//!
//! Every step is a loop over the lanes of fixed-size arrays, plain Rust that the compiler
//! turns into SIMD. [`Tables::eval_chunk`] has that code compiled three times, for
//! AVX-512, for AVX2 with FMA and for the baseline, and picks one at run time. The tables
//! are copies laid out so that one lookup's values sit together: a VNDF node's density
//! beside its CDF, a node's three colours. On Intel CPUs with AVX-512 whose gathers no
//! mitigation slows, they are read by gathers, two values of every lane at a time
//! ([`gather`]); elsewhere by loads per lane, each lane summing its lookups four values at
//! a time in an SSE register ([`Quad`]): gathers of one value each, tried in their place on
//! an AMD Zen 4, were no faster there. Both give the same values to the bit. The input rows of the blocks ahead are
//! prefetched ([`PREFETCH_BLOCKS`]).
//!
//! Directions are normalised in float64 (after an exact scaling by a power of two; 1/|v|
//! from float32's square root and a Newton step) and rounded to float32, their sum too;
//! the horizon test is the float64 path's, so both return 0 for the same pairs. Angles
//! come from a polynomial atan2. The result stays within 1e-4 (relative; median a few
//! 1e-6) of the float64 path where the value is not tiny (`batch_tests.rs`, on the RGL
//! files).
//!
//! [`MeasuredBsdf::eval_pair`]: super::MeasuredBsdf::eval_pair

use std::f32::consts::{FRAC_2_PI, PI, TAU};

#[cfg(target_arch = "x86_64")]
use super::gather;
use super::simd::{atan2, bilinear, bilinear_weights, elevation, lanes, lerp, two, Lanes, Quad, LANES};
use super::warp::Marginal2D;
use super::HORIZON;
use crate::coords::{normalize, Vec3};

/// A power of two that scales `x` (finite and non-zero) into [1, 2), or near it where `x`
/// is subnormal or above 2^1023: an exact scaling without a division.
#[inline(always)]
fn inverse_power_of_two(x: f64) -> f64 {
    let exponent = ((x.to_bits() >> 52) & 0x7ff).clamp(1, 2045);
    f64::from_bits((2046 - exponent) << 52)
}

/// The rows as unit vectors in float64, one array per coordinate, each row first scaled by
/// a power of two near its largest component (rows may be tiny or huge); false if any row
/// is not finite or is zero.
#[inline(always)]
fn unit_rows(rows: &Lanes<Vec3>) -> ([Lanes<f64>; 3], bool) {
    let (mut unit, mut valid) = ([[0f64; LANES]; 3], true);
    for k in 0..LANES {
        let [x, y, z] = rows[k];
        let largest = x.abs().max(y.abs()).max(z.abs());
        valid &= x.is_finite() & y.is_finite() & z.is_finite() & (largest > 0.0);
        let scale = inverse_power_of_two(largest);
        let (x, y, z) = (x * scale, y * scale, z * scale);
        // 1/|v| to float32's accuracy, then one Newton step in float64 (relative error about
        // 1e-14, below what the rounding to float32 keeps): 0.96× the time of a float64
        // square root and division on 512-bit registers (research/performance.md).
        let squared = x * x + y * y + z * z; // in [1, 3): no float32 overflow
        let rough = f64::from(1.0 / (squared as f32).sqrt());
        let norm = rough * (1.5 - 0.5 * squared * rough * rough);
        (unit[0][k], unit[1][k], unit[2][k]) = (x * norm, y * norm, z * norm);
    }
    (unit, valid)
}

/// Whether [`Tables::eval_chunk`] reads the tables by gathers on this CPU ([`gather::preferred`]).
#[cfg(target_arch = "x86_64")]
static GATHERS: std::sync::OnceLock<bool> = std::sync::OnceLock::new();

/// Whether the CPU has what [`Tables::chunk_avx512`] is compiled for.
#[cfg(target_arch = "x86_64")]
fn avx512() -> bool {
    is_x86_feature_detected!("avx512f")
        && is_x86_feature_detected!("avx512bw")
        && is_x86_feature_detected!("avx512dq")
        && is_x86_feature_detected!("avx512vl")
        && is_x86_feature_detected!("fma")
}

/// Blocks ahead whose input rows [`Tables::chunk`] asks for. The hardware's prefetcher did
/// not keep up with the two input streams: with 2 threads, a sixth of the time went on
/// waiting for rows (perf, 2-core AMD EPYC Zen 4). 2, 4 and 8 blocks ahead were within a
/// few percent of each other (research/performance.md).
const PREFETCH_BLOCKS: usize = 4;

/// Asks for the cache lines of `rows[start..start + LANES]` ahead of their loads (nothing
/// off x86_64 or past the end).
#[inline(always)]
fn prefetch_rows(rows: &[Vec3], start: usize) {
    #[cfg(target_arch = "x86_64")]
    if let Some(block) = rows.get(start..start + LANES) {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        const LINE: usize = 64;
        let bytes = std::mem::size_of_val(block);
        for offset in (0..bytes).step_by(LINE) {
            // SAFETY: the address lies inside `block`, and a prefetch reads nothing.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(block.as_ptr().cast::<i8>().add(offset)) };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (rows, start);
}

/// The first three values of each lane's quad, one array per value. (Loops, not
/// `array::map`: a closure left out of line is compiled without the SIMD features.)
#[inline(always)]
fn first_three(quads: &Lanes<[f32; 4]>) -> [Lanes<f32>; 3] {
    let mut values = [[0f32; LANES]; 3];
    for (c, values) in values.iter_mut().enumerate() {
        *values = lanes!(|k| quads[k][c]);
    }
    values
}

/// A node grid of `nx` × `ny`.
#[derive(Clone, Copy, Debug)]
struct Grid {
    nx: u32,
    ny: u32,
}

impl Grid {
    fn plane(self) -> u32 {
        self.nx * self.ny
    }

    /// The patches holding each lane's `pos`: their lower-left nodes' indices in a slice
    /// and rows, and the positions in them. Lane by lane, field by field, so that each
    /// step is one vector operation.
    #[inline(always)]
    #[allow(clippy::manual_clamp)] // clamp keeps a NaN, which the conversion below must not see
    fn patches(self, pos: &[Lanes<f32>; 2]) -> (Lanes<u32>, Lanes<u32>, Lanes<f32>, Lanes<f32>) {
        // max before min: a NaN position becomes 0, so every x and y is in [0, n − 1].
        let x = lanes!(|k| pos[0][k].max(0.0).min(1.0) * (self.nx - 1) as f32);
        let y = lanes!(|k| pos[1][k].max(0.0).min(1.0) * (self.ny - 1) as f32);
        // SAFETY: x and y are in [0, n − 1], and i32 holds n: a table is checked against its
        // grid when read, and a file has at most tensor_file::MAX_BYTES (2^28) bytes, so
        // nx · ny < 2^26. (`as` would check each lane for NaN and overflow one at a time.)
        let column = lanes!(|k| unsafe { x[k].to_int_unchecked::<i32>() }.min(self.nx as i32 - 2));
        let row = lanes!(|k| unsafe { y[k].to_int_unchecked::<i32>() }.min(self.ny as i32 - 2));
        (
            lanes!(|k| (row[k] * self.nx as i32 + column[k]) as u32),
            lanes!(|k| row[k] as u32),
            lanes!(|k| x[k] - column[k] as f32),
            lanes!(|k| y[k] - row[k] as f32),
        )
    }

    /// A one-slice, one-channel table of these nodes at `pos`.
    #[inline(always)]
    fn interpolate<const GATHERS: bool>(self, values: &[f32], pos: &[Lanes<f32>; 2]) -> Lanes<f32> {
        let (node, _, s, t) = self.patches(pos);
        #[cfg(target_arch = "x86_64")]
        if GATHERS {
            let [v00, v10, v01, v11] = gather::patch(values, self.nx, &node);
            return lanes!(|k| bilinear([v00[k], v10[k], v01[k], v11[k]], s[k], t[k]));
        }
        let nx = self.nx as usize;
        lanes!(|k| {
            let node = node[k] as usize;
            let (low, high) = (two(values, node), two(values, node + nx));
            bilinear([low[0], low[1], high[0], high[1]], s[k], t[k])
        })
    }
}

/// A parameter axis of the conditional tables ([`super::warp::ParamAxes`]) in float32.
#[derive(Clone, Debug)]
struct Axis {
    values: Vec<f32>,
    /// 1 / (values[k + 1] − values[k]).
    inverse_steps: Vec<f32>,
    /// Slices between neighbouring values (0 for an axis of one value).
    stride: u32,
}

impl Axis {
    fn new(values: &[f32], stride: usize) -> Axis {
        Axis {
            values: values.to_vec(),
            inverse_steps: values.windows(2).map(|w| 1.0 / (w[1] - w[0])).collect(),
            stride: stride as u32,
        }
    }

    /// The offset of the lower slice around `p` and the upper one's weight, clamped to the
    /// axis's range as [`super::warp::ParamAxes::blend`] does.
    #[inline(always)]
    fn blend(&self, p: &Lanes<f32>) -> (Lanes<u32>, Lanes<f32>) {
        let n = self.values.len();
        if n == 1 {
            return ([0; LANES], [0.0; LANES]);
        }
        // The axis is short (8 values in the RGL files): counting beats a binary search.
        let mut below = [0u32; LANES];
        for &value in &self.values {
            for k in 0..LANES {
                below[k] += (value < p[k]) as u32;
            }
        }
        let index = lanes!(|k| below[k].max(1).min(n as u32 - 1) as usize - 1);
        let upper = lanes!(|k| ((p[k] - self.values[index[k]]) * self.inverse_steps[index[k]]).clamp(0.0, 1.0));
        (lanes!(|k| index[k] as u32 * self.stride), upper)
    }
}

/// The tables of a measurement, rearranged for [`Tables::eval_chunk`].
#[derive(Clone, Debug)]
pub(super) struct Tables {
    isotropic: bool,
    reduction: u32,
    jacobian: bool,
    phi_i: Axis,
    theta_i: Axis,
    vndf: Grid,
    /// Per slice and node: the normalised density, then the conditional CDF.
    vndf_nodes: Vec<f32>,
    /// Per slice and row: the row's integral (its CDF's last value), then the marginal CDF.
    vndf_rows: Vec<f32>,
    rgb: Grid,
    /// Per slice and node: red, green, blue, and a 0 that aligns nodes to 16 bytes.
    rgb_nodes: Vec<f32>,
    ndf: Grid,
    ndf_values: Vec<f32>,
    sigma: Grid,
    sigma_values: Vec<f32>,
}

impl Tables {
    /// Copies of the float64 path's tables (all float32 already).
    pub(super) fn new(bsdf: &super::MeasuredBsdf) -> Tables {
        let grid = |nx: usize, ny: usize| Grid {
            nx: nx as u32,
            ny: ny as u32,
        };
        let Marginal2D {
            axes,
            nx,
            ny,
            data,
            conditional_cdf,
            marginal_cdf,
        } = &bsdf.vndf;
        let vndf_nodes = data.iter().zip(conditional_cdf).flat_map(|(&d, &c)| [d, c]).collect();
        let vndf_rows = conditional_cdf
            .chunks_exact(*nx)
            .zip(marginal_cdf)
            .flat_map(|(row, &marginal)| [row[nx - 1], marginal])
            .collect();
        let plane = bsdf.rgb.nx * bsdf.rgb.ny;
        let rgb_nodes = (bsdf.rgb.data.chunks_exact(3 * plane))
            .flat_map(|slice| (0..plane).flat_map(move |k| [slice[k], slice[plane + k], slice[2 * plane + k], 0.0]))
            .collect();
        let strides = axes.strides();
        Tables {
            isotropic: bsdf.isotropic,
            reduction: bsdf.reduction,
            jacobian: bsdf.jacobian,
            phi_i: Axis::new(&bsdf.phi_i, strides[0]),
            theta_i: Axis::new(&bsdf.theta_i, strides[1]),
            vndf: grid(*nx, *ny),
            vndf_nodes,
            vndf_rows,
            rgb: grid(bsdf.rgb.nx, bsdf.rgb.ny),
            rgb_nodes,
            ndf: grid(bsdf.ndf.nx, bsdf.ndf.ny),
            ndf_values: bsdf.ndf.data.clone(),
            sigma: grid(bsdf.sigma.nx, bsdf.sigma.ny),
            sigma_values: bsdf.sigma.data.clone(),
        }
    }

    /// The BRDF at the pairs `wi`, `wo` into `out`, see [`super::MeasuredBsdf::eval_pair`];
    /// false, and `out` not all filled in, where a row is not finite and non-zero.
    pub(super) fn eval_chunk(&self, wi: &[Vec3], wo: &[Vec3], out: &mut [[f64; 3]]) -> bool {
        // Two slices to blend where only θ_i varies, four where φ_i does too.
        if self.phi_i.values.len() == 1 {
            self.dispatch::<2>(wi, wo, out)
        } else {
            self.dispatch::<4>(wi, wo, out)
        }
    }

    fn dispatch<const CORNERS: usize>(&self, wi: &[Vec3], wo: &[Vec3], out: &mut [[f64; 3]]) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            if avx512() {
                // SAFETY: the CPU has the features the function is compiled for.
                return if *GATHERS.get_or_init(gather::preferred) {
                    unsafe { self.chunk_avx512::<CORNERS, true>(wi, wo, out) }
                } else {
                    unsafe { self.chunk_avx512::<CORNERS, false>(wi, wo, out) }
                };
            }
            if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
                // SAFETY: as above.
                return unsafe { self.chunk_avx2::<CORNERS>(wi, wo, out) };
            }
        }
        self.chunk::<CORNERS, false>(wi, wo, out)
    }

    /// [`Tables::eval_chunk`] in each compiled copy that this CPU can run, for the tests.
    #[cfg(test)]
    pub(super) fn eval_chunk_each_way(&self, wi: &[Vec3], wo: &[Vec3]) -> Vec<Vec<[f64; 3]>> {
        let mut results = Vec::new();
        let mut run = |evaluate: &dyn Fn(&mut [[f64; 3]]) -> bool| {
            let mut out = vec![[0.0; 3]; wi.len()];
            assert!(evaluate(&mut out));
            results.push(out);
        };
        run(&|out| self.chunk::<2, false>(wi, wo, out));
        #[cfg(target_arch = "x86_64")]
        {
            if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
                // SAFETY: the CPU has the features.
                run(&|out| unsafe { self.chunk_avx2::<2>(wi, wo, out) });
            }
            if avx512() {
                // SAFETY: as above (whatever the vendor: the gathers are exact on any).
                run(&|out| unsafe { self.chunk_avx512::<2, false>(wi, wo, out) });
                run(&|out| unsafe { self.chunk_avx512::<2, true>(wi, wo, out) });
            }
            run(&|out| self.dispatch::<2>(wi, wo, out));
        }
        results
    }

    /// The AVX-512 copy, its tables read by gathers ([`gather`]) where `GATHERS`.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512bw,avx512dq,avx512vl,avx2,fma")]
    fn chunk_avx512<const CORNERS: usize, const GATHERS: bool>(
        &self,
        wi: &[Vec3],
        wo: &[Vec3],
        out: &mut [[f64; 3]],
    ) -> bool {
        self.chunk::<CORNERS, GATHERS>(wi, wo, out)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn chunk_avx2<const CORNERS: usize>(&self, wi: &[Vec3], wo: &[Vec3], out: &mut [[f64; 3]]) -> bool {
        self.chunk::<CORNERS, false>(wi, wo, out)
    }

    /// Whole blocks of [`LANES`] pairs, then the rest padded with pairs at the pole; the
    /// tables read by gathers where `GATHERS` (only in a copy compiled for AVX-512).
    #[inline(always)]
    fn chunk<const CORNERS: usize, const GATHERS: bool>(&self, wi: &[Vec3], wo: &[Vec3], out: &mut [[f64; 3]]) -> bool {
        let blocks = wi.chunks_exact(LANES).zip(wo.chunks_exact(LANES));
        for (index, ((wi_block, wo_block), out)) in blocks.zip(out.chunks_exact_mut(LANES)).enumerate() {
            prefetch_rows(wi, (index + PREFETCH_BLOCKS) * LANES);
            prefetch_rows(wo, (index + PREFETCH_BLOCKS) * LANES);
            let (wi_block, wo_block) = (wi_block.try_into().unwrap(), wo_block.try_into().unwrap());
            let Some(values) = self.block::<CORNERS, GATHERS>(wi_block, wo_block) else {
                return false;
            };
            out.copy_from_slice(&values);
        }
        let done = wi.len() - wi.len() % LANES;
        if done < wi.len() {
            let pad =
                |rows: &[Vec3]| -> Lanes<Vec3> { lanes!(|k| rows.get(done + k).copied().unwrap_or([0.0, 0.0, 1.0])) };
            let Some(values) = self.block::<CORNERS, GATHERS>(&pad(wi), &pad(wo)) else {
                return false;
            };
            out[done..].copy_from_slice(&values[..wi.len() - done]);
        }
        true
    }

    /// The values of a block of pairs; None where a row is not finite and non-zero.
    #[inline(always)]
    fn block<const CORNERS: usize, const GATHERS: bool>(
        &self,
        wi: &Lanes<Vec3>,
        wo: &Lanes<Vec3>,
    ) -> Option<Lanes<[f64; 3]>> {
        // Unit directions in float64 (scaled near the largest component first: a row may be tiny or
        // huge) and their sum, the half vector's direction, before rounding to float32: at
        // grazing angles ω_i + ω_o cancels, and float32 inputs would lose its direction.
        // Checking the rows here saves a pass over them.
        let (unit_i, valid_i) = unit_rows(wi);
        let (unit_o, valid_o) = unit_rows(wo);
        let (mut i, mut o, mut m) = ([[0f32; LANES]; 3], [[0f32; LANES]; 3], [[0f32; LANES]; 3]);
        for c in 0..3 {
            i[c] = lanes!(|k| unit_i[c][k] as f32);
            o[c] = lanes!(|k| unit_o[c][k] as f32);
            m[c] = lanes!(|k| (unit_i[c][k] + unit_o[c][k]) as f32);
        }
        if !(valid_i && valid_o) {
            return None;
        }
        // The horizon test as eval_pair makes it, in float64 near the horizon, where float32
        // could decide otherwise. A pair at or below it is evaluated at the pole instead and
        // zeroed at the end.
        let mut above = lanes!(|k| i[2][k] > 1e-8 && o[2][k] > 1e-8);
        // Most blocks lie above it: one vector test passes them.
        if above.contains(&false) {
            for k in 0..LANES {
                if !above[k] && i[2][k] > -1e-8 && o[2][k] > -1e-8 {
                    above[k] = normalize(wi[k])[2] > HORIZON && normalize(wo[k])[2] > HORIZON;
                }
                if !above[k] {
                    for c in 0..3 {
                        (i[c][k], o[c][k], m[c][k]) = ([0.0, 0.0, 1.0][c], [0.0, 0.0, 1.0][c], [0.0, 0.0, 2.0][c]);
                    }
                }
            }
        }
        if self.reduction >= 2 {
            // Mirror ω_i into the measured quarter or half, and ω_o and m with it (eval_pair).
            let flip = |v: f32, sign: f32| if sign.is_sign_positive() { -v } else { v };
            for k in 0..LANES {
                let (sx, sy) = (if self.reduction == 4 { i[0][k] } else { i[1][k] }, i[1][k]);
                for v in [&mut i, &mut o, &mut m] {
                    (v[0][k], v[1][k]) = (flip(v[0][k], sx), flip(v[1][k], sy));
                }
            }
        }

        // Angles of ω_i and of the half vector m (atan2 needs no normalised m), then their
        // unit coordinates u(θ) = √(2θ/π), u(φ) = (φ + π)/2π.
        let (theta_i, phi_i) = (elevation(&i), lanes!(|k| atan2(i[1][k], i[0][k])));
        let theta_m = elevation(&m);
        let u_theta = |theta: f32| (theta * FRAC_2_PI).sqrt();
        let u_wi = [lanes!(|k| u_theta(theta_i[k])), lanes!(|k| (phi_i[k] + PI) / TAU)];
        let u_m = [
            lanes!(|k| u_theta(theta_m[k])),
            lanes!(|k| {
                let phi = atan2(m[1][k], m[0][k]) - if self.isotropic { phi_i[k] } else { 0.0 };
                // In (−1/2, 3/2): wrapped into [0, 1), as u − floor(u).
                let u = (phi + PI) / TAU;
                if u >= 1.0 {
                    u - 1.0
                } else if u < 0.0 {
                    u + 1.0
                } else {
                    u
                }
            }),
        ];

        // The slices around (φ_i, θ_i), shared by the VNDF and the RGB table.
        let (phi_offset, phi_upper) = self.phi_i.blend(&phi_i);
        let (theta_offset, theta_upper) = self.theta_i.blend(&theta_i);
        let mut corners = [([0; LANES], [0.0; LANES]); CORNERS];
        for (c, corner) in corners.iter_mut().enumerate() {
            let (upper_phi, upper_theta) = (c / 2 == 1, c % 2 == 1);
            let slice = lanes!(|k| {
                phi_offset[k]
                    + theta_offset[k]
                    + upper_phi as u32 * self.phi_i.stride
                    + upper_theta as u32 * self.theta_i.stride
            });
            let side = |upper: bool, weight: f32| if upper { weight } else { 1.0 - weight };
            *corner = (
                slice,
                lanes!(|k| side(upper_phi, phi_upper[k]) * side(upper_theta, theta_upper[k])),
            );
        }

        let sample = self.invert_vndf::<CORNERS, GATHERS>(&corners, &u_m);
        let rgb = self.interpolate_rgb::<CORNERS, GATHERS>(&corners, &sample);
        let jacobian = if self.jacobian {
            let ndf = self.ndf.interpolate::<GATHERS>(&self.ndf_values, &u_m);
            let sigma = self.sigma.interpolate::<GATHERS>(&self.sigma_values, &u_wi);
            lanes!(|k| ndf[k] / (4.0 * sigma[k]))
        } else {
            [1.0; LANES]
        };
        Some(lanes!(|k| {
            let scale = if above[k] { jacobian[k] / o[2][k] } else { 0.0 };
            let value = |c: usize| (rgb[c][k].max(0.0) * scale) as f64;
            [value(0), value(1), value(2)]
        }))
    }

    /// [`Marginal2D::invert_blended`] at `pos`: the sample-space point of each lane.
    #[inline(always)]
    fn invert_vndf<const CORNERS: usize, const GATHERS: bool>(
        &self,
        corners: &[(Lanes<u32>, Lanes<f32>); CORNERS],
        pos: &[Lanes<f32>; 2],
    ) -> [Lanes<f32>; 2] {
        let grid = self.vndf;
        let (node, node_row, s, t) = grid.patches(pos);
        // The blended density d and CDF c at the patch's corners, and the rows' integrals r
        // and marginal CDF.
        let [[d00, c00, d10], [d01, c01, d11], [r0, marginal, r1]] =
            self.vndf_values::<CORNERS, GATHERS>(corners, &node, &node_row);
        let x = lanes!(|k| {
            let (c0, c1) = (lerp(d00[k], d01[k], t[k]), lerp(d10[k], d11[k], t[k]));
            let row_total = lerp(r0[k], r1[k], t[k]);
            let row_mass = lerp(c00[k], c01[k], t[k]) + s[k] * (c0 + 0.5 * s[k] * (c1 - c0));
            if row_total > 0.0 {
                row_mass / row_total
            } else {
                0.0
            }
        });
        let y = lanes!(|k| marginal[k] + t[k] * (r0[k] + 0.5 * t[k] * (r1[k] - r0[k])));
        [x, y]
    }

    /// [`gather::vndf`]'s values, by gathers where `GATHERS`, else per lane and slice: a
    /// load of four values for each row of the patch (d and c at a node and at its right
    /// neighbour) and one for the rows (r and the marginal CDF at row j, then at j + 1).
    #[inline(always)]
    fn vndf_values<const CORNERS: usize, const GATHERS: bool>(
        &self,
        corners: &[(Lanes<u32>, Lanes<f32>); CORNERS],
        node: &Lanes<u32>,
        node_row: &Lanes<u32>,
    ) -> [[Lanes<f32>; 3]; 3] {
        let grid = self.vndf;
        #[cfg(target_arch = "x86_64")]
        if GATHERS {
            let (nodes, rows) = (&self.vndf_nodes, &self.vndf_rows);
            return gather::vndf(nodes, rows, (grid.nx, grid.ny), corners, node, node_row);
        }
        let (nx, plane) = (grid.nx as usize, grid.plane() as usize);
        let mut low = [[0f32; 4]; LANES];
        let mut high = [[0f32; 4]; LANES];
        let mut rows = [[0f32; 4]; LANES];
        for k in 0..LANES {
            let (mut l, mut h, mut r) = (Quad::zero(), Quad::zero(), Quad::zero());
            for (slice, weight) in corners {
                let (slice, w) = (slice[k] as usize, weight[k]);
                let node = 2 * (slice * plane + node[k] as usize);
                l = l.add_weighted(w, &self.vndf_nodes, node);
                h = h.add_weighted(w, &self.vndf_nodes, node + 2 * nx);
                r = r.add_weighted(
                    w,
                    &self.vndf_rows,
                    2 * (slice * grid.ny as usize + node_row[k] as usize),
                );
            }
            (low[k], high[k], rows[k]) = (l.to_array(), h.to_array(), r.to_array());
        }
        // Back to one array per value, lanes innermost.
        [first_three(&low), first_three(&high), first_three(&rows)]
    }

    /// The RGB table at `pos`, blended over the slices; per channel.
    #[inline(always)]
    fn interpolate_rgb<const CORNERS: usize, const GATHERS: bool>(
        &self,
        corners: &[(Lanes<u32>, Lanes<f32>); CORNERS],
        pos: &[Lanes<f32>; 2],
    ) -> [Lanes<f32>; 3] {
        let grid = self.rgb;
        let (node, _, s, t) = grid.patches(pos);
        #[cfg(target_arch = "x86_64")]
        if GATHERS {
            return gather::rgb(&self.rgb_nodes, (grid.nx, grid.ny), corners, &node, (&s, &t));
        }
        let nx = grid.nx as usize;
        let plane = grid.plane() as usize;
        let mut sums = [[0f32; 4]; LANES];
        for k in 0..LANES {
            let (s, t) = (s[k], t[k]);
            let bilinear_weights = bilinear_weights(s, t);
            let mut sum = Quad::zero();
            for (slice, weight) in corners {
                let base = slice[k] as usize * plane + node[k] as usize;
                for (offset, b) in [0, 1, nx, nx + 1].into_iter().zip(bilinear_weights) {
                    sum = sum.add_weighted(weight[k] * b, &self.rgb_nodes, 4 * (base + offset));
                }
            }
            sums[k] = sum.to_array();
        }
        first_three(&sums)
    }
}
