//! A simulation run: the vehicle drives its path and the scanner takes a scan every period,
//! with the ground truth and noisy odometry at the scan time.

use rand::SeedableRng;
use rand::rngs::StdRng;

use crate::{
    Laps, LidarModel, Odometer, Pose2, RayCaster, SensorConfig, SimError, TrueCorner, Vehicle,
    VehicleConfig, World,
};

/// The vehicle is stepped at no more than this, seconds, whatever the scan rate.
const MAX_STEP: f64 = 0.01;

/// One scan with what the simulator knows about it.
#[derive(Debug, Clone, PartialEq)]
pub struct SimulatedScan {
    /// 0, 1, 2, ...
    pub seq: u64,
    /// Simulated time of the scan, `seq * period`, nanoseconds from 0.
    pub stamp_ns: u64,
    /// Ground-truth pose of the sensor at the scan time.
    pub pose: Pose2,
    /// One range per beam (REP 117 invalid values), see [`LidarModel::scan`].
    pub ranges: Vec<f32>,
    /// Noisy integrated odometry at the scan time (starts at the true start pose).
    pub odometry: Pose2,
    /// Forward speed measured by the odometry over the last period, m/s.
    pub linear_velocity: f64,
    /// Yaw rate measured by the odometry over the last period, rad/s.
    pub angular_velocity: f64,
}

/// Produces the frames of one run; the same inputs and seed give the same frames.
#[derive(Debug, Clone)]
pub struct Simulation {
    world: World,
    corners: Vec<TrueCorner>,
    caster: RayCaster,
    lidar: LidarModel,
    vehicle: Vehicle,
    odometer: Odometer,
    scan_rng: StdRng,
    odometry_rng: StdRng,
    seq: u64,
    /// Frames after which the run ends even if the vehicle never arrives (a path it cannot
    /// follow must not run forever).
    frame_limit: u64,
    done: bool,
}

impl Simulation {
    /// The world's route driven once.
    pub fn new(
        world: World,
        sensor: SensorConfig,
        vehicle: VehicleConfig,
        seed: u64,
    ) -> Result<Simulation, SimError> {
        Simulation::with_laps(world, sensor, vehicle, seed, Laps::ONE)
    }

    /// The world's route driven `laps` times in a row ([`Vehicle::with_laps`]): one run, its
    /// stamps, sequence numbers and noise carrying on from lap to lap.
    pub fn with_laps(
        world: World,
        sensor: SensorConfig,
        vehicle: VehicleConfig,
        seed: u64,
        laps: Laps,
    ) -> Result<Simulation, SimError> {
        let lidar = LidarModel::new(sensor).map_err(SimError::Sensor)?;
        let odometry = vehicle.odometry.clone();
        let vehicle = Vehicle::with_laps(&world, vehicle, laps)?;
        let odometer = Odometer::new(odometry, vehicle.pose());
        // Separate streams, so turning one noise source off leaves the other unchanged.
        let mut master = StdRng::seed_from_u64(seed);
        let scan_rng = StdRng::from_rng(&mut master);
        let odometry_rng = StdRng::from_rng(&mut master);
        let laps = f64::from(laps.get());
        let expected_s = world.path_length() * laps / world.speed;
        let frame_limit = ((3.0 * expected_s + 60.0 * laps) * lidar.config().rate) as u64;
        Ok(Simulation {
            corners: world.true_corners(),
            caster: RayCaster::new(&world),
            world,
            lidar,
            vehicle,
            odometer,
            scan_rng,
            odometry_rng,
            seq: 0,
            frame_limit,
            done: false,
        })
    }

    pub fn world(&self) -> &World {
        &self.world
    }

    /// [`World::true_corners`], computed once.
    pub fn true_corners(&self) -> &[TrueCorner] {
        &self.corners
    }

    pub fn caster(&self) -> &RayCaster {
        &self.caster
    }

    pub fn sensor(&self) -> &SensorConfig {
        self.lidar.config()
    }

    /// The scan at the current time, then the vehicle moves on by one period. `None` once
    /// the frame at the end of the path's last lap has been returned.
    pub fn next_frame(&mut self) -> Option<SimulatedScan> {
        if self.done {
            return None;
        }
        let pose = self.vehicle.pose();
        let mut ranges = Vec::new();
        self.lidar
            .scan(&self.caster, pose, &mut self.scan_rng, &mut ranges);
        let (linear_velocity, angular_velocity) = self.odometer.velocity();
        let frame = SimulatedScan {
            seq: self.seq,
            stamp_ns: self.seq * self.lidar.config().period_ns(),
            pose,
            ranges,
            odometry: self.odometer.pose(),
            linear_velocity,
            angular_velocity,
        };
        self.seq += 1;
        if self.vehicle.finished() || self.seq >= self.frame_limit {
            self.done = true;
        } else {
            let period = self.lidar.config().period_ns() as f64 * 1e-9;
            let steps = (period / MAX_STEP).ceil().max(1.0);
            for _ in 0..steps as u64 {
                self.vehicle.step(period / steps);
            }
            self.odometer
                .update(self.vehicle.pose(), period, &mut self.odometry_rng);
        }
        Some(frame)
    }
}
