//! A 3x3 covariance over `(x, y, yaw)` as the messages carry it: row by row.

use nalgebra::Matrix3;

/// `matrix` row by row, as a message's `[f64; 9]` covariance field holds it.
pub fn covariance_to_row_major(matrix: &Matrix3<f64>) -> [f64; 9] {
    std::array::from_fn(|i| matrix[(i / 3, i % 3)])
}

/// The matrix of a message's row-major `[f64; 9]` covariance field.
pub fn covariance_from_row_major(row_major: &[f64; 9]) -> Matrix3<f64> {
    Matrix3::from_row_slice(row_major)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_covariance_goes_row_by_row_and_comes_back_the_same() {
        let matrix = Matrix3::new(1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0);
        let row_major = covariance_to_row_major(&matrix);
        assert_eq!(row_major, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
        assert_eq!(covariance_from_row_major(&row_major), matrix);
    }
}
