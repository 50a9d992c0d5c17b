//! Clipping of polylines to a panel: a non-finite point, or one outside the x range, breaks the
//! line into separate runs; where the line leaves or re-enters the y range, it is cut at the
//! border (Liang–Barsky in y), so nothing is drawn outside the axes and nothing inside is lost.
//! Log axes place no value `<= 0`: such a point breaks the line too.

use super::Axis;

/// The part of the segment `p`–`q` (in axis fractions) whose `y` lies in `0..=1`, if any;
/// an end inside is returned unchanged.
fn clip_segment(p: (f64, f64), q: (f64, f64)) -> Option<((f64, f64), (f64, f64))> {
    let dy = q.1 - p.1;
    let (t0, t1) = if dy == 0.0 {
        (0.0, 1.0)
    } else {
        let (a, b) = (-p.1 / dy, (1.0 - p.1) / dy);
        (a.min(b).max(0.0), a.max(b).min(1.0))
    };
    let inside = dy != 0.0 || (0.0..=1.0).contains(&p.1);
    let at = |t: f64| {
        if t <= 0.0 {
            p
        } else if t >= 1.0 {
            q
        } else {
            (p.0 + t * (q.0 - p.0), p.1 + t * dy)
        }
    };
    (inside && t0 <= t1).then(|| (at(t0), at(t1)))
}

/// The drawable runs of the polyline `points` on axes `x`, `y`: a non-finite point, or one
/// outside the x range, breaks the line; the line leaves and re-enters through the y range's
/// ends (clipped, as a plot should).
///
/// ```
/// use edgekf_sim::report::plot::{clip, Axis};
///
/// let line = [(0.0, 0.5), (1.0, f64::NAN), (2.0, 0.5), (3.0, 2.0)];
/// let runs = clip(&line, Axis::Linear(0.0, 3.0), Axis::Linear(0.0, 1.0));
/// // The NaN breaks the line; the last segment is cut where it leaves the axis at y = 1.
/// assert_eq!(runs.len(), 2);
/// let (x, y) = runs[1][1];
/// assert!((x - 7.0 / 3.0).abs() < 1e-12 && (y - 1.0).abs() < 1e-12);
/// ```
pub fn clip(points: &[(f64, f64)], x: Axis, y: Axis) -> Vec<Vec<(f64, f64)>> {
    let mut runs: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut prev: Option<(f64, f64)> = None;
    for &(px, py) in points {
        let cur = x.fraction(px).filter(|f| (0.0..=1.0).contains(f)).zip(y.fraction(py));
        match (prev, cur) {
            (Some(p), Some(q)) => {
                if let Some((a, b)) = clip_segment(p, q) {
                    match runs.last_mut() {
                        Some(run) if run.last() == Some(&a) => run.push(b),
                        _ => runs.push(vec![a, b]),
                    }
                }
            }
            (None, Some(q)) if (0.0..=1.0).contains(&q.1) => runs.push(vec![q]),
            _ => {}
        }
        prev = cur;
    }
    runs.iter().map(|run| run.iter().map(|&(fx, fy)| (x.value(fx), y.value(fy))).collect()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_leave_and_reenter_through_the_border() {
        let points = [(0.0, 0.0), (1.0, 2.0), (2.0, 0.0), (3.0, f64::NAN), (4.0, 0.5), (5.0, 0.5), (6.0, -3.0)];
        let runs = clip(&points, Axis::Linear(0.0, 6.0), Axis::Linear(-1.0, 1.0));
        let expected = [
            vec![(0.0, 0.0), (0.5, 1.0)],
            vec![(1.5, 1.0), (2.0, 0.0)],
            vec![(4.0, 0.5), (5.0, 0.5), (5.0 + 3.0 / 7.0, -1.0)],
        ];
        assert_eq!(runs.len(), expected.len());
        for (run, want) in runs.iter().zip(&expected) {
            assert_eq!(run.len(), want.len());
            for (p, q) in run.iter().zip(want) {
                assert!((p.0 - q.0).abs() < 1e-9 && (p.1 - q.1).abs() < 1e-9, "{runs:?}");
            }
        }
        // Log axes: non-positive values break the line; x outside the range too.
        let points = [(1.0, 1.0), (2.0, 0.0), (3.0, 10.0), (4.0, 10.0), (9.0, 1.0)];
        let runs = clip(&points, Axis::Linear(0.0, 5.0), Axis::Log(0.1, 100.0));
        assert_eq!(runs.len(), 2, "{runs:?}");
        assert_eq!(runs[1].len(), 2);
        assert!((runs[1][0].1 - 10.0).abs() < 1e-9);
    }

    #[test]
    fn nan_breaks_a_line_into_two() {
        let points = [(0.0, 0.1), (1.0, 0.2), (2.0, f64::NAN), (3.0, 0.3), (4.0, 0.4)];
        let runs = clip(&points, Axis::Linear(0.0, 4.0), Axis::Linear(0.0, 1.0));
        assert_eq!(runs, vec![vec![(0.0, 0.1), (1.0, 0.2)], vec![(3.0, 0.3), (4.0, 0.4)]]);
    }

    #[test]
    fn clipped_points_stay_inside_the_axes() {
        let points: Vec<(f64, f64)> = (0..200).map(|k| (k as f64 * 0.05, 3.0 * (k as f64 * 0.3).sin())).collect();
        let runs = clip(&points, Axis::Linear(0.0, 9.0), Axis::Linear(-1.0, 2.0));
        assert!(runs.len() > 5, "the sine leaves and re-enters: {} runs", runs.len());
        for p in runs.iter().flatten() {
            assert!((0.0..=9.0).contains(&p.0) && (-1.0 - 1e-12..=2.0 + 1e-12).contains(&p.1), "{p:?}");
        }
        // A line wholly above the axis draws nothing.
        assert!(clip(&[(0.0, 5.0), (1.0, 6.0)], Axis::Linear(0.0, 1.0), Axis::Linear(0.0, 1.0)).is_empty());
    }
}
