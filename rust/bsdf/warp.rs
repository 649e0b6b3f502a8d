//! Piecewise-bilinear functions on the unit square, conditioned on extra parameters, and
//! the marginal–conditional warp built on them (Dupuy & Jakob 2018, §5).
//!
//! A table of `ny` rows × `nx` columns of nodes spans [0, 1]²: node (x, y) sits at
//! (x / (nx − 1), y / (ny − 1)) and values in between are bilinear. A conditional table
//! holds one such slice per combination of parameter values (the incident angles of a
//! measured BRDF); between those values, slices are blended linearly.
//!
//! [`Marginal2D`] treats a non-negative table as a density. Its warp maps the unit
//! square onto the density's support by inverting first the marginal CDF over rows
//! (y) and then the CDF of the row at the chosen height (x), both continuous, so the
//! map is smooth and has an exact inverse ([`Marginal2D::invert`]). The measured BRDF
//! stores its colour in the warped ("sample") space of its VNDF, and evaluation needs
//! the inverse.
//!
//! Tables are kept in single precision, as the files store them, and the CDFs are
//! rounded to single precision as the reference implementations round them; all
//! arithmetic on them is double precision.

/// Most parameter axes a table may depend on.
pub const MAX_AXES: usize = 3;
const MAX_CORNERS: usize = 1 << MAX_AXES;

/// The parameter axes of a conditional table, outermost (slowest in memory) first.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamAxes {
    values: Vec<Vec<f64>>,
    /// Slices between neighbouring values of each axis; 0 for an axis with one value.
    strides: Vec<usize>,
    slices: usize,
}

impl ParamAxes {
    /// No parameters: one slice.
    pub fn none() -> ParamAxes {
        ParamAxes {
            values: Vec::new(),
            strides: Vec::new(),
            slices: 1,
        }
    }

    /// Axes given by the parameter values their slices sit at: each axis non-empty,
    /// finite and strictly increasing.
    pub fn new(axes: &[&[f32]]) -> Result<ParamAxes, String> {
        if axes.len() > MAX_AXES {
            return Err(format!(
                "{} parameter axes; at most {MAX_AXES} are supported",
                axes.len()
            ));
        }
        let mut strides = vec![0; axes.len()];
        let mut slices = 1usize;
        for (k, axis) in axes.iter().enumerate().rev() {
            if axis.is_empty() {
                return Err(format!("parameter axis {k} has no values"));
            }
            if let Some(i) = axis.iter().position(|v| !v.is_finite()) {
                return Err(format!("parameter axis {k} value {i} is {}", axis[i]));
            }
            if let Some(i) = axis.windows(2).position(|w| w[0] >= w[1]) {
                return Err(format!(
                    "parameter axis {k} is not strictly increasing: {} then {}",
                    axis[i],
                    axis[i + 1]
                ));
            }
            strides[k] = if axis.len() > 1 { slices } else { 0 };
            slices = slices
                .checked_mul(axis.len())
                .ok_or_else(|| "too many parameter slices".to_string())?;
        }
        Ok(ParamAxes {
            values: axes
                .iter()
                .map(|axis| axis.iter().map(|&v| v as f64).collect())
                .collect(),
            strides,
            slices,
        })
    }

    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Per axis, the slices between neighbouring values (0 for an axis of one value).
    pub fn strides(&self) -> &[usize] {
        &self.strides
    }

    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// Slices of a table over these axes.
    pub fn slices(&self) -> usize {
        self.slices
    }

    /// The slices to blend at `params` (one per axis), with their weights. Outside an
    /// axis's range the nearest end's slice is used.
    pub fn blend(&self, params: &[f64]) -> Blend {
        debug_assert_eq!(params.len(), self.values.len());
        let mut blend = Blend {
            len: 1,
            slice: [0; MAX_CORNERS],
            weight: [1.0; MAX_CORNERS],
        };
        for ((values, &stride), &p) in self.values.iter().zip(&self.strides).zip(params) {
            if values.len() == 1 {
                continue;
            }
            let i = find_interval(values.len(), |k| values[k] < p);
            let upper = ((p - values[i]) / (values[i + 1] - values[i])).clamp(0.0, 1.0);
            let (before, base) = (blend, blend.len);
            blend.len = 0;
            for k in 0..base {
                let (slice, weight) = (before.slice[k] + stride * i, before.weight[k]);
                // Corners of weight zero are skipped: every table value is finite.
                for (offset, w) in [(0, 1.0 - upper), (stride, upper)] {
                    if w > 0.0 {
                        blend.slice[blend.len] = slice + offset;
                        blend.weight[blend.len] = weight * w;
                        blend.len += 1;
                    }
                }
            }
        }
        blend
    }
}

/// Slices of a conditional table and their weights, from [`ParamAxes::blend`].
#[derive(Clone, Copy, Debug)]
pub struct Blend {
    len: usize,
    slice: [usize; MAX_CORNERS],
    weight: [f64; MAX_CORNERS],
}

impl Blend {
    /// Σ weight · `table[slice · slice_len + index]`.
    #[inline]
    fn at(&self, table: &[f32], slice_len: usize, index: usize) -> f64 {
        (0..self.len)
            .map(|k| self.weight[k] * table[self.slice[k] * slice_len + index] as f64)
            .sum()
    }
}

/// The largest `k` in `0..=n − 2` for which `below(k)` holds, `below` being true on a
/// prefix of `0..n`; 0 when it holds nowhere.
#[inline]
fn find_interval(n: usize, below: impl Fn(usize) -> bool) -> usize {
    // Binary search for the length of the prefix.
    let (mut lo, mut hi) = (0, n);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if below(mid) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    lo.saturating_sub(1).min(n - 2)
}

/// The patch of an `n`-node axis holding `pos` (clamped to [0, 1]) and the position in it.
#[inline]
fn locate(pos: f64, n: usize) -> (usize, f64) {
    let x = pos.clamp(0.0, 1.0) * (n - 1) as f64;
    let i = (x as usize).min(n - 2);
    (i, x - i as f64)
}

#[inline]
fn lerp(a: f64, b: f64, t: f64) -> f64 {
    a + t * (b - a)
}

/// The t in [0, 1] where the integral of the linear function a → b from 0 reaches `mass`:
/// the root of a t + (b − a) t²/2 = mass, in the form that cancels nothing.
#[inline]
fn invert_linear_integral(a: f64, b: f64, mass: f64) -> f64 {
    let denominator = a + (a * a + 2.0 * mass * (b - a)).max(0.0).sqrt();
    if denominator > 0.0 {
        (2.0 * mass / denominator).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// Checks a table's size against its grid and that its values are finite.
fn check_table(data: &[f32], nx: usize, ny: usize, slices: usize) -> Result<(), String> {
    if nx < 2 || ny < 2 {
        return Err(format!("a {ny} × {nx} grid; both sizes must be at least 2"));
    }
    let expected = slices
        .checked_mul(nx)
        .and_then(|n| n.checked_mul(ny))
        .ok_or_else(|| "too many values".to_string())?;
    if data.len() != expected {
        return Err(format!(
            "{} values for {slices} slices of {ny} × {nx}; expected {expected}",
            data.len()
        ));
    }
    if let Some(i) = data.iter().position(|v| !v.is_finite()) {
        return Err(format!("value {i} is {}", data[i]));
    }
    Ok(())
}

/// A conditional piecewise-bilinear function with `channels` values per node, used as
/// stored (not normalised). Layout: `[slice][channel][y][x]`.
#[derive(Clone, Debug)]
pub struct Interpolant {
    pub(super) axes: ParamAxes,
    pub(super) nx: usize,
    pub(super) ny: usize,
    channels: usize,
    pub(super) data: Vec<f32>,
}

impl Interpolant {
    pub fn new(data: Vec<f32>, nx: usize, ny: usize, channels: usize, axes: ParamAxes) -> Result<Interpolant, String> {
        let slices = axes
            .slices()
            .checked_mul(channels)
            .ok_or_else(|| "too many slices".to_string())?;
        check_table(&data, nx, ny, slices)?;
        Ok(Interpolant {
            axes,
            nx,
            ny,
            channels,
            data,
        })
    }

    /// The values as stored, `[slice][channel][y][x]`.
    pub fn data(&self) -> &[f32] {
        &self.data
    }

    pub fn axes(&self) -> &ParamAxes {
        &self.axes
    }

    /// The value of a one-channel table at `pos` for `params`.
    pub fn eval(&self, pos: [f64; 2], params: &[f64]) -> f64 {
        let [value] = self.eval_channels(&self.axes.blend(params), pos);
        value
    }

    /// All `C` channels at `pos`, for slices blended by `blend` (from this table's axes).
    #[inline]
    pub fn eval_channels<const C: usize>(&self, blend: &Blend, pos: [f64; 2]) -> [f64; C] {
        assert_eq!(C, self.channels, "the table has {} channels", self.channels);
        let (nx, plane) = (self.nx, self.nx * self.ny);
        let (i, s) = locate(pos[0], nx);
        let (j, t) = locate(pos[1], self.ny);
        let corner = j * nx + i;
        std::array::from_fn(|c| {
            let at = |index: usize| blend.at(&self.data, C * plane, c * plane + index);
            let (v00, v10, v01, v11) = (at(corner), at(corner + 1), at(corner + nx), at(corner + nx + 1));
            lerp(lerp(v00, v10, s), lerp(v01, v11, s), t)
        })
    }
}

/// A conditional density on [0, 1]² (a non-negative bilinear table normalised per
/// slice) with its marginal–conditional warp.
#[derive(Clone, Debug)]
pub struct Marginal2D {
    pub(super) axes: ParamAxes,
    pub(super) nx: usize,
    pub(super) ny: usize,
    /// The table divided by its integral in node units (so the density on [0, 1]² is
    /// these values times (nx − 1)(ny − 1)).
    pub(super) data: Vec<f32>,
    /// Per slice and row, the integral of the row from column 0 to each node.
    pub(super) conditional_cdf: Vec<f32>,
    /// Per slice, the integral of the rows from row 0 to each row.
    pub(super) marginal_cdf: Vec<f32>,
}

impl Marginal2D {
    /// Builds the warp of `data` (`axes.slices()` slices of `ny` × `nx`), which must be
    /// finite and non-negative with a positive integral in every slice.
    pub fn new(data: &[f32], nx: usize, ny: usize, axes: ParamAxes) -> Result<Marginal2D, String> {
        check_table(data, nx, ny, axes.slices())?;
        if let Some(i) = data.iter().position(|&v| v < 0.0) {
            return Err(format!("value {i} is negative ({}); a density is not", data[i]));
        }
        let plane = nx * ny;
        let mut normalised = vec![0f32; data.len()];
        let mut conditional_cdf = vec![0f32; data.len()];
        let mut marginal_cdf = vec![0f32; axes.slices() * ny];
        for slice in 0..axes.slices() {
            let values = &data[slice * plane..(slice + 1) * plane];
            let conditional = &mut conditional_cdf[slice * plane..(slice + 1) * plane];
            let marginal = &mut marginal_cdf[slice * ny..(slice + 1) * ny];
            // Trapezoids along each row, accumulated in double precision.
            for (row, cdf) in values.chunks_exact(nx).zip(conditional.chunks_exact_mut(nx)) {
                let mut sum = 0f64;
                for x in 1..nx {
                    sum += 0.5 * (row[x - 1] as f64 + row[x] as f64);
                    cdf[x] = sum as f32;
                }
            }
            // Trapezoids over the row totals (each row's integral is linear between rows).
            let mut sum = 0f64;
            for y in 1..ny {
                sum += 0.5 * (conditional[y * nx - 1] as f64 + conditional[(y + 1) * nx - 1] as f64);
                marginal[y] = sum as f32;
            }
            let total = marginal[ny - 1];
            if !(total > 0.0 && total.is_finite()) {
                return Err(format!(
                    "slice {slice} integrates to {total}; a density needs a positive integral"
                ));
            }
            let scale = 1.0 / total;
            conditional.iter_mut().for_each(|v| *v *= scale);
            marginal.iter_mut().for_each(|v| *v *= scale);
            for (out, &v) in normalised[slice * plane..(slice + 1) * plane].iter_mut().zip(values) {
                *out = v * scale;
            }
        }
        Ok(Marginal2D {
            axes,
            nx,
            ny,
            data: normalised,
            conditional_cdf,
            marginal_cdf,
        })
    }

    pub fn axes(&self) -> &ParamAxes {
        &self.axes
    }

    fn patch_area_inverse(&self) -> f64 {
        ((self.nx - 1) * (self.ny - 1)) as f64
    }

    /// The density at `pos` for `params`; it integrates to 1 over [0, 1]².
    pub fn eval(&self, pos: [f64; 2], params: &[f64]) -> f64 {
        let blend = self.axes.blend(params);
        let (nx, plane) = (self.nx, self.nx * self.ny);
        let (i, s) = locate(pos[0], nx);
        let (j, t) = locate(pos[1], self.ny);
        let at = |index: usize| blend.at(&self.data, plane, index);
        let corner = j * nx + i;
        let (v00, v10, v01, v11) = (at(corner), at(corner + 1), at(corner + nx), at(corner + nx + 1));
        lerp(lerp(v00, v10, s), lerp(v01, v11, s), t) * self.patch_area_inverse()
    }

    /// Warps a point `u` of the unit square to a point distributed by the density;
    /// returns it with the density there.
    pub fn sample(&self, u: [f64; 2], params: &[f64]) -> ([f64; 2], f64) {
        let blend = self.axes.blend(params);
        let (nx, ny, plane) = (self.nx, self.ny, self.nx * self.ny);
        let u = [u[0].clamp(0.0, 1.0), u[1].clamp(0.0, 1.0)];
        let cdf = |index: usize| blend.at(&self.conditional_cdf, plane, index);
        let data = |index: usize| blend.at(&self.data, plane, index);

        // The row band: marginal CDF, then the position in the band, where the row
        // integral is linear from r0 to r1.
        let marginal = |y: usize| blend.at(&self.marginal_cdf, ny, y);
        let j = find_interval(ny, |y| marginal(y) < u[1]);
        let (r0, r1) = (cdf(j * nx + nx - 1), cdf((j + 1) * nx + nx - 1));
        let t = invert_linear_integral(r0, r1, u[1] - marginal(j));

        // The column, in the row interpolated at t.
        let target = u[0] * lerp(r0, r1, t);
        let row_cdf = |x: usize| lerp(cdf(j * nx + x), cdf((j + 1) * nx + x), t);
        let i = find_interval(nx, |x| row_cdf(x) < target);
        let corner = j * nx + i;
        let c0 = lerp(data(corner), data(corner + nx), t);
        let c1 = lerp(data(corner + 1), data(corner + nx + 1), t);
        let s = invert_linear_integral(c0, c1, target - row_cdf(i));

        let pos = [(i as f64 + s) / (nx - 1) as f64, (j as f64 + t) / (ny - 1) as f64];
        (pos, lerp(c0, c1, s) * self.patch_area_inverse())
    }

    /// The inverse of [`Marginal2D::sample`]: the point of the unit square that warps to
    /// `pos`, with the density at `pos`.
    pub fn invert(&self, pos: [f64; 2], params: &[f64]) -> ([f64; 2], f64) {
        self.invert_blended(&self.axes.blend(params), pos)
    }

    /// [`Marginal2D::invert`] for slices already blended by this table's axes.
    #[inline]
    pub fn invert_blended(&self, blend: &Blend, pos: [f64; 2]) -> ([f64; 2], f64) {
        let (nx, ny, plane) = (self.nx, self.ny, self.nx * self.ny);
        let (i, s) = locate(pos[0], nx);
        let (j, t) = locate(pos[1], ny);
        let cdf = |index: usize| blend.at(&self.conditional_cdf, plane, index);
        let data = |index: usize| blend.at(&self.data, plane, index);

        let corner = j * nx + i;
        let c0 = lerp(data(corner), data(corner + nx), t);
        let c1 = lerp(data(corner + 1), data(corner + nx + 1), t);
        let (r0, r1) = (cdf(j * nx + nx - 1), cdf((j + 1) * nx + nx - 1));

        // x: the row's integral up to pos, over its total (an empty row maps to 0).
        let row_total = lerp(r0, r1, t);
        let row_mass = lerp(cdf(corner), cdf(corner + nx), t) + s * (c0 + 0.5 * s * (c1 - c0));
        let x = if row_total > 0.0 { row_mass / row_total } else { 0.0 };
        // y: the marginal integral up to pos.
        let y = blend.at(&self.marginal_cdf, ny, j) + t * (r0 + 0.5 * t * (r1 - r0));
        ([x, y], lerp(c0, c1, s) * self.patch_area_inverse())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::bsdf::synthetic::TestRng as Rng;

    /// A positive, bumpy table over two parameter axes (3 and 4 values) of 9 × 7 nodes,
    /// with a zero row and a zero column to exercise empty regions.
    fn bumpy() -> (Vec<f32>, usize, usize, ParamAxes) {
        let (nx, ny) = (9, 7);
        let axes = ParamAxes::new(&[&[-1.0, 0.0, 2.0], &[0.0, 0.3, 0.9, 1.5]]).unwrap();
        let mut rng = Rng(7);
        let data = (0..axes.slices() * nx * ny)
            .map(|k| {
                let (y, x) = ((k / nx) % ny, k % nx);
                if y == 2 || x == 4 {
                    0.0
                } else {
                    (0.05 + rng.next() * rng.next() * 3.0) as f32
                }
            })
            .collect();
        (data, nx, ny, axes)
    }

    #[test]
    fn blend_weights() {
        let axes = ParamAxes::new(&[&[5.0], &[0.0, 1.0, 3.0], &[0.0, 1.0, 2.0]]).unwrap();
        assert_eq!(axes.slices(), 9);
        assert_eq!(axes.strides, [0, 3, 1]);
        let blend = axes.blend(&[123.0, 2.0, 1.0]);
        let pairs: Vec<(usize, f64)> = (0..blend.len).map(|k| (blend.slice[k], blend.weight[k])).collect();
        assert_eq!(pairs, [(4, 0.5), (7, 0.5)]);
        // Outside the range: the end slices, no extrapolation.
        let blend = axes.blend(&[0.0, -4.0, 9.0]);
        assert_eq!((blend.len, blend.slice[0], blend.weight[0]), (1, 2, 1.0));
        assert!(ParamAxes::new(&[&[0.0, 0.0]]).is_err());
        assert!(ParamAxes::new(&[&[]]).is_err());
        assert!(ParamAxes::new(&[&[f32::NAN]]).is_err());
    }

    #[test]
    fn sample_and_invert_round_trip() {
        let (data, nx, ny, axes) = bumpy();
        let warp = Marginal2D::new(&data, nx, ny, axes).unwrap();
        let mut rng = Rng(99);
        for _ in 0..20_000 {
            let params = [rng.next() * 4.0 - 1.5, rng.next() * 1.8 - 0.1];
            let u = [rng.next(), rng.next()];
            let (pos, pdf) = warp.sample(u, &params);
            assert!(pos.iter().all(|p| (0.0..=1.0).contains(p)), "{pos:?}");
            let (back, pdf_back) = warp.invert(pos, &params);
            assert!(
                (back[0] - u[0]).abs() < 1e-6 && (back[1] - u[1]).abs() < 1e-6,
                "{u:?} → {pos:?} → {back:?}"
            );
            assert!((pdf - pdf_back).abs() <= 1e-9 * pdf.max(1.0));
            assert!((warp.eval(pos, &params) - pdf).abs() <= 1e-9 * pdf.max(1.0));
            assert!(pdf > 0.0, "sampled a point of zero density at {pos:?}");
        }
    }

    #[test]
    fn invert_then_sample_round_trip() {
        let (data, nx, ny, axes) = bumpy();
        let warp = Marginal2D::new(&data, nx, ny, axes).unwrap();
        let mut rng = Rng(3);
        for _ in 0..20_000 {
            let params = [rng.next() * 3.0 - 1.0, rng.next() * 1.5];
            let pos = [rng.next(), rng.next()];
            let (u, pdf) = warp.invert(pos, &params);
            if pdf < 1e-3 {
                continue; // the warp is not one-to-one where the density vanishes
            }
            let (back, _) = warp.sample(u, &params);
            assert!(
                (back[0] - pos[0]).abs() < 1e-6 && (back[1] - pos[1]).abs() < 1e-6,
                "{pos:?} → {u:?} → {back:?}"
            );
        }
    }

    #[test]
    fn density_integrates_to_one_and_warp_is_monotone() {
        let (data, nx, ny, axes) = bumpy();
        let warp = Marginal2D::new(&data, nx, ny, axes).unwrap();
        for params in [[-1.0, 0.0], [0.5, 0.7], [2.0, 1.5]] {
            let n = 400;
            let mut sum = 0.0;
            for a in 0..n {
                for b in 0..n {
                    let pos = [(a as f64 + 0.5) / n as f64, (b as f64 + 0.5) / n as f64];
                    sum += warp.eval(pos, &params);
                }
            }
            assert!(
                (sum / (n * n) as f64 - 1.0).abs() < 1e-4,
                "{params:?}: {}",
                sum / (n * n) as f64
            );
            // The inverse is monotone in y along a column and in x along a row.
            let ys: Vec<f64> = (0..=50)
                .map(|k| warp.invert([0.3, k as f64 / 50.0], &params).0[1])
                .collect();
            assert!(ys.windows(2).all(|w| w[0] <= w[1] + 1e-12));
            assert!(ys[0].abs() < 1e-7 && (ys[50] - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn constant_density_warps_to_the_identity() {
        let axes = ParamAxes::new(&[&[0.0, 1.0]]).unwrap();
        let warp = Marginal2D::new(&[2.5; 2 * 5 * 4], 5, 4, axes).unwrap();
        for pos in [[0.0, 0.0], [0.3, 0.8], [1.0, 0.45], [0.99, 1.0]] {
            let (u, pdf) = warp.invert(pos, &[0.4]);
            assert!((u[0] - pos[0]).abs() < 1e-7 && (u[1] - pos[1]).abs() < 1e-7);
            assert!((pdf - 1.0).abs() < 1e-7);
        }
    }

    #[test]
    fn interpolant_is_bilinear_per_channel() {
        // Channel c holds c + 2x − y at node (x, y) in unit-square coordinates; slices
        // along the one axis add 10 × its value.
        let (nx, ny) = (5, 3);
        let axis = [0.0f32, 1.0];
        let data: Vec<f32> = (0..2 * 3 * ny * nx)
            .map(|k| {
                let (slice, c, y, x) = (k / (3 * nx * ny), (k / (nx * ny)) % 3, (k / nx) % ny, k % nx);
                c as f32 + 2.0 * x as f32 / (nx - 1) as f32 - y as f32 / (ny - 1) as f32 + 10.0 * axis[slice]
            })
            .collect();
        let table = Interpolant::new(data, nx, ny, 3, ParamAxes::new(&[&axis]).unwrap()).unwrap();
        let blend = table.axes().blend(&[0.25]);
        let values: [f64; 3] = table.eval_channels(&blend, [0.3, 0.6]);
        for (c, value) in values.into_iter().enumerate() {
            assert!((value - (c as f64 + 0.6 - 0.6 + 2.5)).abs() < 1e-6, "{c}: {value}");
        }
        assert!(Interpolant::new(vec![0.0; 10], 5, 3, 1, ParamAxes::none()).is_err());
        assert!(Interpolant::new(vec![0.0; 5], 5, 1, 1, ParamAxes::none()).is_err());
    }

    #[test]
    fn rejects_bad_densities() {
        let axes = || ParamAxes::new(&[&[0.0, 1.0]]).unwrap();
        let mut data = vec![1.0f32; 2 * 3 * 3];
        data[12] = -0.5;
        assert!(Marginal2D::new(&data, 3, 3, axes()).unwrap_err().contains("negative"));
        let mut data = vec![1.0f32; 2 * 3 * 3];
        data[9..].fill(0.0);
        assert!(Marginal2D::new(&data, 3, 3, axes())
            .unwrap_err()
            .contains("slice 1 integrates to 0"));
        assert!(Marginal2D::new(&[f32::NAN; 18], 3, 3, axes()).is_err());
    }
}
