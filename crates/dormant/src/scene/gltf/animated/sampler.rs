//! A glTF animation sampler read into checked keys, and its value at any time: STEP, LINEAR
//! (spherical for rotations) and CUBICSPLINE as the glTF 2.0 specification defines them
//! (section 3.11 and appendix C). A sampler evaluated at one of its own key times returns
//! that key as stored, and between two bit-identical keys returns the key: resting stretches
//! written as two keys stay exact.

use glam::{Quat, Vec3};

/// How a sampler interpolates between keys.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Interpolation {
    Step,
    Linear,
    /// Each key carries an in-tangent, a value and an out-tangent.
    CubicSpline,
}

/// A value a channel animates: a translation or scale (`Vec3`) or a rotation (`Quat`).
pub(crate) trait Animated: Copy {
    fn lerp(a: Self, b: Self, s: f32) -> Self;
    /// The cubic Hermite spline of glTF's appendix C (tangents already scaled by the
    /// interval).
    fn hermite(p0: Self, m0: Self, p1: Self, m1: Self, s: f32) -> Self;
    fn bits_equal(a: &Self, b: &Self) -> bool;
    fn scaled(self, k: f32) -> Self;
    fn is_zero(&self) -> bool;
    fn is_finite(&self) -> bool;
    /// Whether a key value (not a tangent) is one glTF allows.
    fn is_valid_key(&self) -> bool;
    /// What a valid key is, for messages.
    const VALID_KEY: &'static str;
}

impl Animated for Vec3 {
    fn lerp(a: Self, b: Self, s: f32) -> Self {
        a.lerp(b, s)
    }

    fn hermite(p0: Self, m0: Self, p1: Self, m1: Self, s: f32) -> Self {
        let (s2, s3) = (s * s, s * s * s);
        p0 * (2.0 * s3 - 3.0 * s2 + 1.0)
            + m0 * (s3 - 2.0 * s2 + s)
            + p1 * (-2.0 * s3 + 3.0 * s2)
            + m1 * (s3 - s2)
    }

    fn bits_equal(a: &Self, b: &Self) -> bool {
        a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits)
    }

    fn scaled(self, k: f32) -> Self {
        self * k
    }

    fn is_zero(&self) -> bool {
        *self == Vec3::ZERO
    }

    fn is_finite(&self) -> bool {
        Vec3::is_finite(*self)
    }

    fn is_valid_key(&self) -> bool {
        Vec3::is_finite(*self)
    }

    const VALID_KEY: &'static str = "finite";
}

impl Animated for Quat {
    fn lerp(a: Self, b: Self, s: f32) -> Self {
        a.slerp(b, s)
    }

    fn hermite(p0: Self, m0: Self, p1: Self, m1: Self, s: f32) -> Self {
        let v = |q: Quat| glam::Vec4::from(q);
        let (s2, s3) = (s * s, s * s * s);
        let r = v(p0) * (2.0 * s3 - 3.0 * s2 + 1.0)
            + v(m0) * (s3 - 2.0 * s2 + s)
            + v(p1) * (-2.0 * s3 + 3.0 * s2)
            + v(m1) * (s3 - s2);
        let r = r.normalize_or_zero();
        if r == glam::Vec4::ZERO {
            Quat::IDENTITY
        } else {
            Quat::from_vec4(r)
        }
    }

    fn bits_equal(a: &Self, b: &Self) -> bool {
        a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits)
    }

    /// A tangent scaled component-wise (tangents are not unit quaternions).
    fn scaled(self, k: f32) -> Self {
        Quat::from_vec4(glam::Vec4::from(self) * k)
    }

    fn is_zero(&self) -> bool {
        glam::Vec4::from(*self) == glam::Vec4::ZERO
    }

    fn is_finite(&self) -> bool {
        Quat::is_finite(*self)
    }

    /// A rotation key must be a unit quaternion (as glTF requires), give or take rounding.
    fn is_valid_key(&self) -> bool {
        Quat::is_finite(*self) && (self.length() - 1.0).abs() < 1e-3
    }

    const VALID_KEY: &'static str = "a finite unit quaternion";
}

/// A checked sampler: at least one key, strictly increasing finite times, finite values,
/// three values per key for CUBICSPLINE.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Sampler<T> {
    interpolation: Interpolation,
    times: Vec<f32>,
    values: Vec<T>,
}

impl<T: Animated> Sampler<T> {
    /// Checks `times` and `values` (as read from the accessors); the error is the cause.
    pub(crate) fn new(interpolation: Interpolation, times: Vec<f32>, values: Vec<T>) -> Result<Self, String> {
        let per_key = if interpolation == Interpolation::CubicSpline { 3 } else { 1 };
        if times.is_empty() {
            return Err("the sampler has no keys".into());
        }
        if values.len() != times.len() * per_key {
            return Err(format!(
                "{} output values for {} input times (expected {})",
                values.len(),
                times.len(),
                times.len() * per_key
            ));
        }
        if let Some(i) = times.iter().position(|t| !t.is_finite() || *t < 0.0) {
            return Err(format!("input time {i} is {} (times must be finite and not negative)", times[i]));
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(format!("output value {i} is not finite"));
        }
        let key = |i: usize| if per_key == 3 { 3 * i + 1 } else { i };
        if let Some(i) = (0..times.len()).map(key).find(|&i| !values[i].is_valid_key()) {
            return Err(format!("output value {i} is not {}", T::VALID_KEY));
        }
        if let Some(i) = times.windows(2).position(|w| w[1] <= w[0]) {
            return Err(format!(
                "input times are not increasing at key {}: {} then {}",
                i + 1,
                times[i],
                times[i + 1]
            ));
        }
        Ok(Self { interpolation, times, values })
    }

    /// The last key's time.
    pub(crate) fn end(&self) -> f32 {
        *self.times.last().expect("a checked sampler has keys")
    }

    /// The key value `k` (the middle of a CUBICSPLINE triplet).
    fn key(&self, k: usize) -> T {
        match self.interpolation {
            Interpolation::CubicSpline => self.values[3 * k + 1],
            _ => self.values[k],
        }
    }

    /// The value at time `t`: the first key before the first time, the last after the last.
    pub(crate) fn at(&self, t: f32) -> T {
        let next = self.times.partition_point(|&k| k <= t);
        if next == 0 {
            return self.key(0);
        }
        let k = next - 1;
        if next == self.times.len() || self.times[k] == t {
            return self.key(k);
        }
        let (t0, t1) = (self.times[k], self.times[next]);
        let s = (t - t0) / (t1 - t0);
        let (a, b) = (self.key(k), self.key(next));
        match self.interpolation {
            Interpolation::Step => a,
            _ if T::bits_equal(&a, &b) && self.flat_between(k) => a,
            Interpolation::Linear => T::lerp(a, b, s),
            Interpolation::CubicSpline => {
                let dt = t1 - t0;
                let (out, inn) = (self.values[3 * k + 2], self.values[3 * next]);
                T::hermite(a, out.scaled(dt), b, inn.scaled(dt), s)
            }
        }
    }

    /// Whether the curve between keys `k` and `k + 1` is flat when their values are equal
    /// (always for LINEAR; for CUBICSPLINE only with zero tangents).
    fn flat_between(&self, k: usize) -> bool {
        match self.interpolation {
            Interpolation::CubicSpline => {
                self.values[3 * k + 2].is_zero() && self.values[3 * k + 3].is_zero()
            }
            _ => true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn linear(times: &[f32], values: &[f32]) -> Sampler<Vec3> {
        let values = values.iter().map(|&v| Vec3::new(v, 2.0 * v, 0.1)).collect();
        Sampler::new(Interpolation::Linear, times.to_vec(), values).unwrap()
    }

    #[test]
    fn a_key_time_gives_the_key_as_stored_and_times_outside_clamp() {
        let s = linear(&[0.1, 0.3, 0.7], &[1.0, 1.0 / 3.0, 5.0]);
        assert_eq!(s.at(0.3).to_array(), [1.0 / 3.0, 2.0 / 3.0, 0.1]);
        assert_eq!(s.at(0.0), s.at(0.1));
        assert_eq!(s.at(9.0).x, 5.0);
        assert!((s.at(0.5).x - (1.0 / 3.0 + 5.0) / 2.0).abs() < 1e-6);
    }

    #[test]
    fn between_two_identical_keys_every_interpolation_gives_the_key_bit_for_bit() {
        let q = Quat::from_euler(glam::EulerRot::XYZ, 0.3, 1.1, -0.7);
        for interpolation in [Interpolation::Linear, Interpolation::Step] {
            let s = Sampler::new(interpolation, vec![0.0, 1.0], vec![q, q]).unwrap();
            for t in [0.1, 0.37, 0.999] {
                assert_eq!(s.at(t).to_array().map(f32::to_bits), q.to_array().map(f32::to_bits));
            }
        }
        let zero = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0);
        let cubic =
            Sampler::new(Interpolation::CubicSpline, vec![0.0, 1.0], vec![zero, q, zero, zero, q, zero])
                .unwrap();
        assert_eq!(cubic.at(0.37).to_array().map(f32::to_bits), q.to_array().map(f32::to_bits));
    }

    #[test]
    fn step_holds_the_earlier_key_and_cubic_spline_follows_its_tangents() {
        let step = Sampler::new(Interpolation::Step, vec![0.0, 1.0], vec![Vec3::ZERO, Vec3::ONE]).unwrap();
        assert_eq!(step.at(0.99), Vec3::ZERO);
        assert_eq!(step.at(1.0), Vec3::ONE);
        // p(s) = s³ as a Hermite curve: p0 0, m0 0, p1 1, m1 3 over an interval of 2 s.
        let v = |x: f32| Vec3::splat(x);
        let cubic = Sampler::new(
            Interpolation::CubicSpline,
            vec![0.0, 2.0],
            vec![v(0.0), v(0.0), v(0.0), v(1.5), v(1.0), v(0.0)],
        )
        .unwrap();
        assert!((cubic.at(1.0).x - 0.125).abs() < 1e-6);
    }

    #[test]
    fn malformed_samplers_are_refused_with_their_cause() {
        let err = |times: Vec<f32>, n: usize, i| Sampler::new(i, times, vec![Vec3::ZERO; n]).unwrap_err();
        assert!(err(vec![], 0, Interpolation::Linear).contains("no keys"));
        assert!(err(vec![0.0, 1.0], 3, Interpolation::Linear).contains("3 output values for 2 input times"));
        assert!(err(vec![0.0, 1.0], 2, Interpolation::CubicSpline).contains("expected 6"));
        assert!(err(vec![0.0, 0.0], 2, Interpolation::Step).contains("not increasing"));
        assert!(err(vec![f32::NAN], 1, Interpolation::Step).contains("finite"));
        let nan = Sampler::new(Interpolation::Step, vec![0.0], vec![Vec3::NAN]).unwrap_err();
        assert!(nan.contains("not finite"), "{nan}");
    }
}
