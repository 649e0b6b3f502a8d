//! The floating-point types the transform runs in.

/// Floating-point types the transform runs in.
pub trait Real: realfft::FftNum + realfft::num_traits::Float + Default {
    fn of(value: f64) -> Self;
}
impl Real for f32 {
    fn of(value: f64) -> Self {
        value as f32
    }
}
impl Real for f64 {
    fn of(value: f64) -> Self {
        value
    }
}
