//! Paper 003's spring adaptation as seen from a drag frame: a load is
//! pulled again until Δy/Δx (how far the surface followed over how far
//! the hand moved since the grab) lands in [`SPRING_BAND`], at most
//! [`SPRING_ITERATIONS`] solves. One loop for the single-surface engine
//! and the product engine.

use glam::DVec3;

/// Most repetitions of one drag frame while the spring adapts.
pub const SPRING_ITERATIONS: usize = 12;
/// The band paper 003 keeps the spring's Δy/Δx in.
pub const SPRING_BAND: (f64, f64) = (0.8, 1.2);

/// Runs `frame` (one drag solve: where the icon is, and whatever else the
/// caller keeps from the last solve) once, and for a load (`is_load`)
/// again while the ratio of the icon's motion from `from` to the hand's
/// (`from` → `xyz`) is outside [`SPRING_BAND`], at most
/// [`SPRING_ITERATIONS`] times. Returns the last solve's answer.
pub fn spring_to_band<T, E>(
    from: DVec3,
    xyz: DVec3,
    is_load: bool,
    mut frame: impl FnMut() -> Result<(DVec3, T), E>,
) -> Result<(DVec3, T), E> {
    let mut last = frame()?;
    let dx = (xyz - from).length();
    if !is_load || dx < 1e-9 {
        return Ok(last);
    }
    for _ in 1..SPRING_ITERATIONS {
        let ratio = (last.0 - from).length() / dx;
        if (SPRING_BAND.0..=SPRING_BAND.1).contains(&ratio) {
            break;
        }
        last = frame()?;
    }
    Ok(last)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn repeats_a_load_until_in_band_and_a_constraint_once() {
        // A surface that follows 0.1, 0.5, 0.9 of the hand on successive
        // solves: in band at the third.
        let follow = [0.1, 0.5, 0.9, 1.0];
        let hand = DVec3::new(0.0, 0.0, 1.0);
        let mut calls = 0;
        let (at, n) = spring_to_band::<_, ()>(DVec3::ZERO, hand, true, || {
            calls += 1;
            Ok((hand * follow[calls - 1], calls))
        })
        .unwrap();
        assert_eq!((at, n), (hand * 0.9, 3));
        let mut calls = 0;
        let (_, n) = spring_to_band::<_, ()>(DVec3::ZERO, hand, false, || {
            calls += 1;
            Ok((DVec3::ZERO, calls))
        })
        .unwrap();
        assert_eq!(n, 1);
        // Never in band: stops at the limit.
        let mut calls = 0;
        spring_to_band::<_, ()>(DVec3::ZERO, hand, true, || {
            calls += 1;
            Ok((DVec3::ZERO, ()))
        })
        .unwrap();
        assert_eq!(calls, SPRING_ITERATIONS);
    }
}
