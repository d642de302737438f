//! Small dense linear systems, as the pose and the calibration solve them.

/// Solves the square system `a x = b` by Gaussian elimination with partial pivoting and back
/// substitution (`a` and `b` are overwritten); `None` when a pivot is smaller than `tiny` in
/// magnitude (the system is singular, as far as that says).
pub(crate) fn solve<R: AsRef<[f64]> + AsMut<[f64]>>(a: &mut [R], b: &mut [f64], tiny: f64) -> Option<Vec<f64>> {
    let n = b.len();
    for col in 0..n {
        let pivot = (col..n).max_by(|&i, &j| a[i].as_ref()[col].abs().total_cmp(&a[j].as_ref()[col].abs()))?;
        if a[pivot].as_ref()[col].abs() < tiny {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        let pivot_row = a[col].as_ref().to_vec();
        for row in col + 1..n {
            let factor = a[row].as_ref()[col] / pivot_row[col];
            if factor != 0.0 {
                for (value, pivot_value) in a[row].as_mut().iter_mut().zip(&pivot_row).skip(col) {
                    *value -= factor * pivot_value;
                }
                b[row] -= factor * b[col];
            }
        }
    }
    let mut x = vec![0.0; n];
    for row in (0..n).rev() {
        let coefficients = a[row].as_ref();
        let tail: f64 = (row + 1..n).map(|k| coefficients[k] * x[k]).sum();
        x[row] = (b[row] - tail) / coefficients[row];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_system_is_solved_and_a_singular_one_refused() {
        let mut a = [[2.0, 1.0, -1.0], [-3.0, -1.0, 2.0], [-2.0, 1.0, 2.0]];
        let x = solve(&mut a, &mut [8.0, -11.0, -3.0], 1e-12).unwrap();
        for (got, want) in x.iter().zip([2.0, 3.0, -1.0]) {
            assert!((got - want).abs() < 1e-12, "{x:?}");
        }
        let mut singular = [[1.0, 2.0], [2.0, 4.0]];
        assert_eq!(solve(&mut singular, &mut [1.0, 2.0], 1e-12), None);
    }
}
