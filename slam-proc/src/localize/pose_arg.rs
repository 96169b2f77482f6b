//! A pose given on the command line: `x,y,yaw` in metres and radians.

use slam_geom::Pose2;

/// Why a pose argument was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("`{text}` is not a pose x,y,yaw (metres, radians): {reason}")]
pub struct PoseArgError {
    pub text: String,
    pub reason: &'static str,
}

/// Reads `x,y,yaw`; the yaw is wrapped.
pub fn parse_pose(text: &str) -> Result<Pose2, PoseArgError> {
    let refuse = |reason| PoseArgError {
        text: text.to_owned(),
        reason,
    };
    let values: Vec<f64> = text
        .split(',')
        .map(|v| v.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| refuse("a value is not a number"))?;
    let [x, y, yaw] = values[..] else {
        return Err(refuse("it needs exactly three values"));
    };
    if !(x.is_finite() && y.is_finite() && yaw.is_finite()) {
        return Err(refuse("a value is not finite"));
    }
    Ok(Pose2::new(x, y, yaw))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_three_numbers_and_refuses_the_rest() {
        let pose = parse_pose("1.5, -2,0.25").unwrap();
        assert_eq!((pose.x, pose.y, pose.yaw), (1.5, -2.0, 0.25));
        assert!((parse_pose("0,0,7").unwrap().yaw - (7.0 - std::f64::consts::TAU)).abs() < 1e-12);
        for bad in ["", "1,2", "1,2,3,4", "a,b,c", "1,2,inf", "1,,2"] {
            assert!(parse_pose(bad).is_err(), "{bad}");
        }
        assert!(parse_pose("1,2").unwrap_err().to_string().contains("three"));
    }
}
