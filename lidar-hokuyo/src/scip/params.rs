//! The sensor's own description of its geometry and timing: the reply to `PP`.

use super::ScipError;
use super::reply::Information;

/// What `PP` reports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SensorParams {
    /// `MODL`: the model.
    pub model: String,
    /// `DMIN`: shortest valid range, mm. Smaller values are error codes.
    pub dmin_mm: u32,
    /// `DMAX`: longest valid range, mm.
    pub dmax_mm: u32,
    /// `ARES`: steps in a full turn.
    pub ares: u32,
    /// `AMIN`: first step of the measurement area.
    pub amin: u32,
    /// `AMAX`: last step of the measurement area.
    pub amax: u32,
    /// `AFRT`: the step that looks straight ahead (bearing 0).
    pub afrt: u32,
    /// `SCAN`: motor speed, revolutions per minute (one scan per revolution).
    pub scan_rpm: u32,
}

impl SensorParams {
    /// The UTM-30LX, whose recordings the tests replay: 270 degrees in 1081 steps of
    /// 0.25 degrees, 23 mm to 60 m, 40 scans a second.
    pub fn utm_30lx() -> Self {
        Self {
            model: "UTM-30LX".into(),
            dmin_mm: 23,
            dmax_mm: 60_000,
            ares: 1440,
            amin: 0,
            amax: 1080,
            afrt: 540,
            scan_rpm: 2400,
        }
    }

    /// Reads the parameters from a `PP` reply and checks they describe a usable sensor.
    pub fn from_information(info: &Information) -> Result<Self, ScipError> {
        let number = |name: &'static str| -> Result<u32, ScipError> {
            let value = info.get(name).ok_or(ScipError::MissingParameter(name))?;
            value.trim().parse().map_err(|_| ScipError::BadParameter {
                name,
                value: value.to_owned(),
            })
        };
        let params = Self {
            model: info.get("MODL").unwrap_or("unknown").to_owned(),
            dmin_mm: number("DMIN")?,
            dmax_mm: number("DMAX")?,
            ares: number("ARES")?,
            amin: number("AMIN")?,
            amax: number("AMAX")?,
            afrt: number("AFRT")?,
            scan_rpm: number("SCAN")?,
        };
        let bad = |name: &'static str, value: u32| ScipError::BadParameter {
            name,
            value: value.to_string(),
        };
        if params.ares == 0 {
            return Err(bad("ARES", params.ares));
        }
        if params.scan_rpm == 0 {
            return Err(bad("SCAN", params.scan_rpm));
        }
        if params.amin > params.amax {
            return Err(bad("AMIN (after AMAX)", params.amin));
        }
        if params.amax > u32::from(super::command::MAX_STEP) {
            return Err(bad("AMAX", params.amax));
        }
        if params.dmin_mm >= params.dmax_mm {
            return Err(bad("DMIN (not below DMAX)", params.dmin_mm));
        }
        Ok(params)
    }

    /// The `PP` reply's lines for these parameters, in the sensor's order.
    pub fn to_information(&self) -> Information {
        Information(vec![
            ("MODL".into(), self.model.clone()),
            ("DMIN".into(), self.dmin_mm.to_string()),
            ("DMAX".into(), self.dmax_mm.to_string()),
            ("ARES".into(), self.ares.to_string()),
            ("AMIN".into(), self.amin.to_string()),
            ("AMAX".into(), self.amax.to_string()),
            ("AFRT".into(), self.afrt.to_string()),
            ("SCAN".into(), self.scan_rpm.to_string()),
        ])
    }

    /// Bearing of `step` in the sensor frame (x forward, counter-clockwise), radians:
    /// `(step - AFRT) * 2 pi / ARES`. Fractional steps give the middle of a cluster.
    pub fn step_angle(&self, step: f64) -> f64 {
        (step - f64::from(self.afrt)) * std::f64::consts::TAU / f64::from(self.ares)
    }

    /// Time of one revolution, seconds.
    pub fn scan_time(&self) -> f64 {
        60.0 / f64::from(self.scan_rpm)
    }

    /// Time between two adjacent steps, seconds.
    pub fn step_time(&self) -> f64 {
        self.scan_time() / f64::from(self.ares)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn info(pairs: &[(&str, &str)]) -> Information {
        Information(
            pairs
                .iter()
                .map(|(n, v)| ((*n).to_owned(), (*v).to_owned()))
                .collect(),
        )
    }

    #[test]
    fn the_documentation_example_reads() {
        let params = SensorParams::from_information(&info(&[
            ("MODL", "URG-04LX(Hokuyo Automatic Co.,Ltd.)"),
            ("DMIN", "20"),
            ("DMAX", "5600"),
            ("ARES", "1024"),
            ("AMIN", "44"),
            ("AMAX", "725"),
            ("AFRT", "384"),
            ("SCAN", "600"),
        ]))
        .unwrap();
        assert_eq!(params.dmax_mm, 5600);
        assert_eq!(params.afrt, 384);
        assert!((params.scan_time() - 0.1).abs() < 1e-12);
    }

    #[test]
    fn utm_geometry() {
        let utm = SensorParams::utm_30lx();
        assert_eq!(
            SensorParams::from_information(&utm.to_information()),
            Ok(utm.clone())
        );
        let pi = std::f64::consts::PI;
        assert!((utm.step_angle(0.0) + 0.75 * pi).abs() < 1e-12);
        assert!((utm.step_angle(540.0)).abs() < 1e-12);
        assert!((utm.step_angle(1080.0) - 0.75 * pi).abs() < 1e-12);
        assert!((utm.scan_time() - 0.025).abs() < 1e-12);
        assert!((utm.step_time() - 0.025 / 1440.0).abs() < 1e-15);
    }

    #[test]
    fn missing_or_nonsense_parameters_are_refused() {
        let mut pairs = SensorParams::utm_30lx().to_information().0;
        pairs.retain(|(n, _)| n != "ARES");
        assert_eq!(
            SensorParams::from_information(&Information(pairs)),
            Err(ScipError::MissingParameter("ARES"))
        );
        for (name, value) in [
            ("ARES", "0"),
            ("SCAN", "0"),
            ("SCAN", "fast"),
            ("AMIN", "2000"),
            ("AMAX", "20000"),
            ("DMIN", "70000"),
            ("DMAX", "-1"),
        ] {
            let mut pairs = SensorParams::utm_30lx().to_information().0;
            for (n, v) in &mut pairs {
                if n == name {
                    *v = value.to_owned();
                }
            }
            assert!(
                SensorParams::from_information(&Information(pairs)).is_err(),
                "{name}={value}"
            );
        }
    }
}
