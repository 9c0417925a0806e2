//! Transcendental functions that give the same bits on every platform.
//!
//! `f64::sin`, `asin`, `atan2`, `log2`, `cbrt` and the like call the platform's C library (glibc
//! natively, wasi-libc's in WebAssembly), whose results differ in the last bit for some inputs;
//! the fine-tuning amplifies one bit into a different mesh. These are the `libm` crate's (a
//! pure-Rust port of musl's, the same code on every target), so a run in the browser makes the
//! native mesh bit for bit. The pipeline calls these, never the standard library's.
//! (`sqrt`, `floor`, `mul_add` and `powi` are exact or compiled the same everywhere.)
//!
//! Also the roundings of an `f64` to the `f32` next above or below it, for `f32` structures that
//! must stay conservative ([`f32_at_least`], [`f32_at_most`]).

/// Sine.
#[inline]
pub fn sin(x: f64) -> f64 {
    libm::sin(x)
}

/// Cosine.
#[inline]
pub fn cos(x: f64) -> f64 {
    libm::cos(x)
}

/// Arcsine.
#[inline]
pub fn asin(x: f64) -> f64 {
    libm::asin(x)
}

/// Arccosine.
#[inline]
pub fn acos(x: f64) -> f64 {
    libm::acos(x)
}

/// The angle of `(x, y)`: `atan2(y, x)`, as `y.atan2(x)`.
#[inline]
pub fn atan2(y: f64, x: f64) -> f64 {
    libm::atan2(y, x)
}

/// Base-2 logarithm.
#[inline]
pub fn log2(x: f64) -> f64 {
    libm::log2(x)
}

/// Cube root.
#[inline]
pub fn cbrt(x: f64) -> f64 {
    libm::cbrt(x)
}

/// The least `f32` at least `x` (`x` itself when it is one; infinite beyond `f32`'s range).
#[inline]
pub fn f32_at_least(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) < x { f.next_up() } else { f }
}

/// The greatest `f32` at most `x` (`x` itself when it is one; infinite beyond `f32`'s range).
#[inline]
pub fn f32_at_most(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) > x { f.next_down() } else { f }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn they_agree_with_the_standard_library_to_an_ulp() {
        let close = |a: f64, b: f64| (a - b).abs() <= 2.0 * f64::EPSILON * a.abs().max(b.abs());
        for i in 1..2000 {
            let x = f64::from(i) * 0.001_7;
            let s = (x * 0.5).min(1.0);
            assert!(close(sin(x), x.sin()) && close(cos(x), x.cos()), "{x}");
            assert!(close(asin(s), s.asin()) && close(acos(s), s.acos()), "{s}");
            assert!(close(atan2(x, 1.0 - x), x.atan2(1.0 - x)), "{x}");
            assert!(close(log2(x), x.log2()) && close(cbrt(x), x.cbrt()), "{x}");
        }
        assert_eq!(log2(8.0), 3.0);
        assert_eq!(cbrt(27.0), 3.0);
    }

    /// Each rounding lands on its side of `x` and no `f32` lies between it and `x`.
    #[test]
    fn f32_roundings_are_on_their_side_and_tight() {
        let mut rng = crate::rng::Rng::new(5);
        let mut xs = vec![
            0.0,
            -0.0,
            1.0,
            0.1,
            -0.1,
            1e-40,
            -1e-40,
            1e20 + 1.0,
            3.5e38,
            -3.5e38,
        ];
        xs.extend(
            (0..1000).map(|_| (rng.next_f64() - 0.5) * 10f64.powi(rng.below(20) as i32 - 10)),
        );
        for x in xs {
            let (up, down) = (f32_at_least(x), f32_at_most(x));
            assert!(
                f64::from(up) >= x && f64::from(down) <= x,
                "{x}: {down} {up}"
            );
            if up.is_finite() {
                assert!(f64::from(up.next_down()) < x, "{x}: {up} is not the least");
            }
            if down.is_finite() {
                assert!(
                    f64::from(down.next_up()) > x,
                    "{x}: {down} is not the greatest"
                );
            }
        }
    }
}
