//! Decimation of long series for drawing: the minimum and the maximum of each pixel column, in
//! time order. A plot then holds a few points per pixel instead of every sample, and a spike of
//! one sample still shows; a column with no finite value becomes one NaN point, which breaks
//! the line there (see [`clip`](super::clip())).

/// Decimates `(t, y)` for a plot `columns` pixels wide: the minimum and the maximum of each
/// column in time order, so spikes survive. A column without a finite value gives a NaN point,
/// which breaks the line.
///
/// ```
/// use edgekf_sim::report::plot::min_max;
///
/// let t: Vec<f64> = (0..10_000).map(f64::from).collect();
/// let mut y = vec![0.0; 10_000];
/// y[4321] = 7.0; // a spike of one sample
/// let drawn = min_max(&t, &y, 400);
/// assert!(drawn.len() <= 800 && drawn.contains(&(4321.0, 7.0)));
/// ```
pub fn min_max(t: &[f64], y: &[f64], columns: usize) -> Vec<(f64, f64)> {
    let points: Vec<(f64, f64)> = t.iter().copied().zip(y.iter().copied()).collect();
    min_max_points(&points, columns)
}

/// [`min_max`] on points.
pub fn min_max_points(points: &[(f64, f64)], columns: usize) -> Vec<(f64, f64)> {
    let n = points.len();
    let columns = columns.max(1);
    if n <= 2 * columns {
        return points.to_vec();
    }
    let mut out = Vec::with_capacity(2 * columns);
    for c in 0..columns {
        let bucket = &points[c * n / columns..(c + 1) * n / columns];
        let finite = || bucket.iter().enumerate().filter(|(_, p)| p.1.is_finite());
        let lo = finite().min_by(|a, b| a.1 .1.total_cmp(&b.1 .1)).map(|(i, _)| i);
        let hi = finite().max_by(|a, b| a.1 .1.total_cmp(&b.1 .1)).map(|(i, _)| i);
        match (lo, hi) {
            (Some(lo), Some(hi)) => {
                out.push(bucket[lo.min(hi)]);
                if lo != hi {
                    out.push(bucket[lo.max(hi)]);
                }
            }
            _ => out.push((bucket[0].0, f64::NAN)),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::plot::{clip, Axis};

    #[test]
    fn min_max_keeps_spikes_and_breaks_at_gaps() {
        let t: Vec<f64> = (0..10_000).map(|k| k as f64).collect();
        let mut y = vec![0.0; 10_000];
        y[1234] = 50.0;
        y[7000] = -40.0;
        y[5000..5100].fill(f64::NAN);
        let d = min_max(&t, &y, 100);
        assert!(d.len() <= 200);
        assert!(d.contains(&(1234.0, 50.0)) && d.contains(&(7000.0, -40.0)));
        assert_eq!(d.iter().filter(|p| p.1.is_nan()).count(), 1);
        let runs = clip(&d, Axis::Linear(0.0, 10_000.0), Axis::Linear(-50.0, 50.0));
        assert_eq!(runs.len(), 2);
        assert_eq!(runs.iter().map(Vec::len).sum::<usize>(), d.len() - 1);
        // Short series are left alone.
        assert_eq!(min_max(&t[..10], &y[..10], 100).len(), 10);
    }

    #[test]
    fn min_max_keeps_time_order_within_a_column() {
        // One column of four samples: the maximum comes before the minimum.
        let points = [(0.0, 1.0), (1.0, 9.0), (2.0, -9.0), (3.0, 2.0), (4.0, 0.0), (5.0, 0.0)];
        assert_eq!(min_max_points(&points[..4], 1), vec![(1.0, 9.0), (2.0, -9.0)]);
        // Two columns of three: each gives its extremes in time order.
        assert_eq!(min_max_points(&points, 2), vec![(1.0, 9.0), (2.0, -9.0), (3.0, 2.0), (4.0, 0.0)]);
    }
}
