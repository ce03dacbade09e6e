//! Summary statistics of repeated measurements.

/// Minimum, mean and maximum of a sample: the one place lamina computes them (the bench's
/// summaries, the tables' value ranges, the furnace, the viewer's frame times, the report).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MinMeanMax {
    pub min: f64,
    pub mean: f64,
    pub max: f64,
}

impl MinMeanMax {
    /// `None` for an empty sample. The mean sums in iteration order; a NaN reaches the mean
    /// but not the extremes (`f64::min`/`f64::max` skip it).
    pub fn of(values: impl IntoIterator<Item = f64>) -> Option<Self> {
        let (mut min, mut max, mut sum, mut n) = (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0usize);
        for v in values {
            min = min.min(v);
            max = max.max(v);
            sum += v;
            n += 1;
        }
        (n > 0).then(|| Self {
            min,
            mean: sum / n as f64,
            max,
        })
    }
}

/// min / median / mean / max / sample standard deviation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Summary {
    pub min: f64,
    pub median: f64,
    pub mean: f64,
    pub max: f64,
    pub stdev: f64,
}

impl Summary {
    /// `None` for an empty sample or one with a non-finite value.
    pub fn of(values: &[f64]) -> Option<Self> {
        if values.is_empty() || values.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        let n = sorted.len();
        let median = if n % 2 == 1 {
            sorted[n / 2]
        } else {
            0.5 * (sorted[n / 2 - 1] + sorted[n / 2])
        };
        let MinMeanMax { min, mean, max } = MinMeanMax::of(sorted.iter().copied())?;
        let var = if n > 1 {
            sorted.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64
        } else {
            0.0
        };
        Some(Self {
            min,
            median,
            mean,
            max,
            stdev: var.sqrt(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summary_of_a_known_sample() {
        let s = Summary::of(&[4.0, 1.0, 3.0, 2.0]).unwrap();
        assert_eq!((s.min, s.median, s.mean, s.max), (1.0, 2.5, 2.5, 4.0));
        assert!((s.stdev - (5.0f64 / 3.0).sqrt()).abs() < 1e-12);
        let s = Summary::of(&[7.0]).unwrap();
        assert_eq!((s.median, s.stdev), (7.0, 0.0));
        assert!(Summary::of(&[]).is_none());
        assert!(Summary::of(&[1.0, f64::NAN]).is_none());
    }

    #[test]
    fn min_mean_max_of_a_known_sample() {
        let s = MinMeanMax::of([4.0, 1.0, 3.0, 2.0]).unwrap();
        assert_eq!((s.min, s.mean, s.max), (1.0, 2.5, 4.0));
        assert!(MinMeanMax::of([]).is_none());
    }
}
