//! Synthetic material files, for tests and benchmarks where the real files are absent.

use std::f32::consts::{FRAC_PI_2, PI};

use super::tensor_file::{encode, f32_bytes, Dtype, FieldData};

/// The arrays of an RGB material file, each a shape and its values in C order.
#[derive(Clone, Debug)]
pub struct MaterialArrays {
    pub description: String,
    pub phi_i: Vec<f32>,
    pub theta_i: Vec<f32>,
    /// `(ny, nx)` over (azimuth, √(2θ/π)) of the microfacet normal.
    pub ndf: (Vec<usize>, Vec<f32>),
    /// `(ny, nx)` over (azimuth, √(2θ/π)) of the incident direction.
    pub sigma: (Vec<usize>, Vec<f32>),
    /// `(phi_i, theta_i, ny, nx)`.
    pub vndf: (Vec<usize>, Vec<f32>),
    /// `(phi_i, theta_i, 3, ny, nx)`.
    pub rgb: (Vec<usize>, Vec<f32>),
    pub jacobian: bool,
}

/// A shape and the values of `f` at each of its indices, in C order.
pub fn tabulate<const R: usize>(shape: [usize; R], f: impl Fn([usize; R]) -> f32) -> (Vec<usize>, Vec<f32>) {
    let total = shape.iter().product();
    let values = (0..total)
        .map(|flat| {
            let mut index = [0; R];
            let mut rest = flat;
            for k in (0..R).rev() {
                index[k] = rest % shape[k];
                rest /= shape[k];
            }
            f(index)
        })
        .collect();
    (shape.to_vec(), values)
}

impl MaterialArrays {
    /// A smooth glossy material: a Beckmann-like lobe of roughness `alpha` over a
    /// coloured base, at the resolutions of the RGL files (8 incident elevations,
    /// 128² VNDF nodes, 32² RGB nodes), with `n_phi` incident azimuths over 2π.
    pub fn example(alpha: f32, n_phi: usize) -> MaterialArrays {
        let theta_i: Vec<f32> = (0..8).map(|k| k as f32 / 7.0 * FRAC_PI_2).collect();
        let phi_i: Vec<f32> = if n_phi == 1 {
            vec![0.0]
        } else {
            (0..n_phi)
                .map(|k| -PI + 2.0 * PI * k as f32 / (n_phi - 1) as f32)
                .collect()
        };
        // √(2θ/π) ↦ a Beckmann-like density in θ_m.
        let lobe = |u: f32| {
            let theta = u * u * FRAC_PI_2;
            let tan = theta.tan().min(1e3);
            (-(tan * tan) / (alpha * alpha)).exp() / theta.cos().max(1e-3).powi(4)
        };
        let node = |k: usize, n: usize| k as f32 / (n - 1) as f32;
        MaterialArrays {
            description: format!("synthetic glossy material (alpha {alpha})"),
            ndf: tabulate([2, 128], |[_, x]| lobe(node(x, 128)) / (PI * alpha * alpha)),
            sigma: tabulate([2, 128], |[_, x]| {
                (node(x, 128) * node(x, 128) * FRAC_PI_2).cos().max(0.05)
            }),
            vndf: tabulate([n_phi, 8, 128, 128], |[_, t, _, x]| {
                lobe(node(x, 128)) * (1.0 + 0.3 * node(t, 8)) + 1e-4
            }),
            rgb: tabulate([n_phi, 8, 3, 32, 32], |[p, t, c, y, x]| {
                let base = [0.6, 0.35, 0.1][c];
                base * (1.0 - 0.5 * node(x, 32)) + 0.05 * node(y, 32) + 0.02 * (t + p) as f32
            }),
            phi_i,
            theta_i,
            jacobian: true,
        }
    }

    /// The bytes of the `.bsdf` file holding these arrays, fields in the RGL files' order.
    pub fn encode(&self) -> Vec<u8> {
        let field =
            |name: &'static str, (shape, values): &(Vec<usize>, Vec<f32>)| (name, shape.clone(), f32_bytes(values));
        let float_fields = [
            ("phi_i", vec![self.phi_i.len()], f32_bytes(&self.phi_i)),
            ("theta_i", vec![self.theta_i.len()], f32_bytes(&self.theta_i)),
            field("sigma", &self.sigma),
            field("ndf", &self.ndf),
            field("vndf", &self.vndf),
            field("rgb", &self.rgb),
        ];
        let version = [1u32, 0].iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>();
        let description = self.description.as_bytes();
        let description_shape = [description.len()];
        let mut fields = vec![
            FieldData {
                name: "version",
                dtype: Dtype::UInt32,
                shape: &[2],
                data: &version,
            },
            FieldData {
                name: "description",
                dtype: Dtype::UInt8,
                shape: &description_shape,
                data: description,
            },
        ];
        fields.extend(float_fields.iter().map(|(name, shape, data)| FieldData {
            name,
            dtype: Dtype::Float32,
            shape,
            data,
        }));
        let jacobian = [self.jacobian as u8];
        fields.push(FieldData {
            name: "jacobian",
            dtype: Dtype::UInt8,
            shape: &[1],
            data: &jacobian,
        });
        encode(&fields)
    }
}

/// The tests' random numbers: xorshift64*, uniform in [0, 1), seeded by the tuple's value.
#[cfg(test)]
pub(crate) struct TestRng(pub u64);

#[cfg(test)]
impl TestRng {
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A direction in the upper hemisphere, z ≥ `z_min`.
    pub fn upper(&mut self, z_min: f64) -> [f64; 3] {
        let z = z_min + (1.0 - z_min) * self.next();
        let phi = std::f64::consts::TAU * self.next();
        let rho = (1.0 - z * z).sqrt();
        [rho * phi.cos(), rho * phi.sin(), z]
    }
}
