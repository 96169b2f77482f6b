//! The run's own keys, the sources' sections, the grid and the recording.

use super::{Range, Section, set, unset};

const RATE_NOTE: &str = "0 = lockstep, else at least 0.001";

pub const RUN: Section = Section {
    table: "",
    about: "slam-launch itself: the source, scoring, stall times, a saved map.",
    settings: &[
        set(
            "source",
            "",
            Range::words("sim, replay or hokuyo"),
            "Where the scans come from (--source; --replay implies replay).",
        ),
        unset(
            "relations",
            "",
            Range::words("a relations file (t1 t2 x y z roll pitch yaw)"),
            "\"aces.relations\"",
            "Ground-truth relations to score the run against (--relations); a replay of DIR/NAME.clf finds DIR/NAME.relations.",
        ),
        set(
            "stall_warning",
            "s",
            Range::closed(0.5, 86_400.0),
            "A stage without progress this long is named on the console (--stall-warning).",
        ),
        set(
            "stall_limit",
            "s",
            Range::closed(0.5, 86_400.0).and("at least stall_warning"),
            "A stage without progress this long fails the run (--stall-limit).",
        ),
        unset(
            "map",
            "",
            Range::words("a run's output directory"),
            "\"runs/office\"",
            "A saved map to map on top of, or with localize to localize on (--map).",
        ),
        set(
            "localize",
            "",
            Range::ANY,
            "Localize on the saved map without changing it (--localize).",
        ),
        unset(
            "initial_pose",
            "m, m, rad",
            Range::words("x,y,yaw in the map's frame; needs map"),
            "\"0,0,0\"",
            "Where the robot starts in the saved map (--initial-pose); unset = search the whole map.",
        ),
    ],
};

pub const SIM: Section = Section {
    table: "sim",
    about: "lidar-sim: the simulated world and its pacing.",
    settings: &[
        set(
            "world",
            "",
            Range::words("hall, office, corridor or a world file (JSON)"),
            "The world to drive through (--world).",
        ),
        set(
            "frames",
            "scans",
            Range::ANY,
            "Scans to publish; 0 = until the end of the world's path, every lap of it (--frames).",
        ),
        set(
            "laps",
            "",
            Range::closed(1.0, 1000.0),
            "Times to drive the world's route in a row: round again if it ends where it starts, else back and forth (--laps).",
        ),
        set(
            "rate",
            "scans/s",
            Range::closed(0.0, 1000.0).and(RATE_NOTE),
            "Scans per second; 0 = lockstep, lossless and repeatable (--rate).",
        ),
        set(
            "seed",
            "",
            Range::ANY,
            "Seed of the simulated noise (--seed).",
        ),
        set(
            "odometry",
            "",
            Range::ANY,
            "Publish noisy wheel odometry too (--odometry).",
        ),
    ],
};

pub const SIM_SENSOR: Section = Section {
    table: "sim.sensor",
    about: "The simulated scanner; the defaults are a Hokuyo UTM-30LX.",
    settings: &[
        set("beams", "", Range::closed(1.0, 8192.0), "Beams per scan."),
        set(
            "angle_min",
            "rad",
            Range::closed(-std::f64::consts::PI, std::f64::consts::PI),
            "Bearing of the first beam (0 = forward, counter-clockwise).",
        ),
        set(
            "angle_increment",
            "rad",
            Range::POSITIVE.and("every beam within one turn"),
            "Bearing step between neighbouring beams.",
        ),
        set(
            "range_min",
            "m",
            Range::NON_NEGATIVE,
            "Shortest range the scanner reports.",
        ),
        set(
            "range_max",
            "m",
            Range::POSITIVE.and("above range_min"),
            "Longest range the scanner reports.",
        ),
        set(
            "rate",
            "Hz",
            Range::closed(0.1, 1e6),
            "Scans per second of simulated time (the time step is its inverse).",
        ),
        set(
            "noise_sigma",
            "m",
            Range::NON_NEGATIVE,
            "Range noise standard deviation up to noise_knee.",
        ),
        set(
            "noise_knee",
            "m",
            Range::NON_NEGATIVE,
            "Range beyond which the noise grows.",
        ),
        set(
            "noise_slope",
            "m/m",
            Range::NON_NEGATIVE,
            "Growth of the noise standard deviation per metre beyond the knee.",
        ),
        set(
            "dropout",
            "",
            Range::FRACTION,
            "Probability that a beam returns nothing usable (NaN).",
        ),
    ],
};

pub const SIM_VEHICLE: Section = Section {
    table: "sim.vehicle",
    about: "The simulated vehicle, a pure-pursuit follower of the world's path.",
    settings: &[
        set("max_yaw_rate", "rad/s", Range::POSITIVE, "Fastest turn."),
        set(
            "max_accel",
            "m/s^2",
            Range::POSITIVE,
            "Strongest speeding up and braking.",
        ),
        set(
            "lookahead",
            "m",
            Range::POSITIVE,
            "Distance of the carrot ahead along the path: longer cuts corners wider and turns smoother.",
        ),
    ],
};

pub const SIM_VEHICLE_ODOMETRY: Section = Section {
    table: "sim.vehicle.odometry",
    about: "The simulated wheel odometry's error, as random walks.",
    settings: &[
        set(
            "sigma_forward",
            "m/sqrt(m)",
            Range::NON_NEGATIVE,
            "Forward error per square root of the distance travelled.",
        ),
        set(
            "sigma_lateral",
            "m/sqrt(m)",
            Range::NON_NEGATIVE,
            "Sideways error per square root of the distance travelled.",
        ),
        set(
            "sigma_yaw_per_m",
            "rad/sqrt(m)",
            Range::NON_NEGATIVE,
            "Heading error from driving, per square root of the distance.",
        ),
        set(
            "sigma_yaw_per_rad",
            "rad/sqrt(rad)",
            Range::NON_NEGATIVE,
            "Heading error from turning, per square root of the angle turned.",
        ),
    ],
};

pub const REPLAY: Section = Section {
    table: "replay",
    about: "lidar-replay: a recorded log, a run's run.mcap or a ROS 2 bag (source = \"replay\").",
    settings: &[
        unset(
            "file",
            "",
            Range::words("a log file or a bag directory"),
            "\"aces.clf\"",
            "The log to replay (--replay).",
        ),
        unset(
            "every",
            "scans",
            Range::at_least(1.0),
            "3",
            "Publish every N-th scan (and all the odometry): a harder log (--replay-every).",
        ),
        unset(
            "max_range",
            "m",
            Range::POSITIVE,
            "5.0",
            "Ranges beyond this become no-returns: a shorter sensor (--replay-max-range).",
        ),
        set(
            "format",
            "",
            Range::words("seed-csv, carmen, mcap or rosbag2"),
            "The log's format (--format; --replay of a directory, a .db3 or a .mcap of ROS 2 messages is rosbag2, another .mcap is mcap).",
        ),
        set(
            "rate",
            "x",
            Range::closed(0.0, 1000.0).and(RATE_NOTE),
            "Speed relative to the log's own timing, 1 = as recorded; 0 = lockstep (--rate).",
        ),
        set(
            "odometry",
            "",
            Range::ANY,
            "Publish the log's odometry when it has any (--no-odometry sets false).",
        ),
        set(
            "frames",
            "scans",
            Range::ANY,
            "Scans to publish; 0 = the whole log (--frames).",
        ),
        unset(
            "reorder_window",
            "s",
            Range::words("[0, 3600], checked by lidar-replay"),
            "2.0",
            "Log time to wait for lines written out of time order; unset = lidar-replay's default.",
        ),
        set(
            "start",
            "scans",
            Range::ANY,
            "The log's scan to start at, from 0 (--replay-start).",
        ),
        unset(
            "scan_topic",
            "",
            Range::words("a sensor_msgs/msg/LaserScan topic of the bag"),
            "\"/scan\"",
            "A ROS 2 bag's scans (--scan-topic); unset = the bag's only LaserScan topic.",
        ),
        set(
            "odom_source",
            "",
            Range::words("auto, odom or tf"),
            "A ROS 2 bag's odometry: nav_msgs/msg/Odometry (odom), /tf from odom_frame to base_frame (tf), or auto: Odometry if the bag has it, else /tf (--odom-source).",
        ),
        unset(
            "odom_topic",
            "",
            Range::words("a nav_msgs/msg/Odometry topic of the bag"),
            "\"/odom\"",
            "A ROS 2 bag's Odometry topic (--odom-topic); unset = the bag's only one.",
        ),
        set(
            "base_frame",
            "",
            Range::words("a frame of the bag"),
            "A ROS 2 bag's robot frame (REP 105): the odometry's child frame and the parent of the laser's mount on /tf_static (--base-frame).",
        ),
        set(
            "odom_frame",
            "",
            Range::words("a frame of the bag"),
            "A ROS 2 bag's odometry frame, for odometry from /tf (--odom-frame).",
        ),
    ],
};

pub const HOKUYO: Section = Section {
    table: "hokuyo",
    about: "lidar-hokuyo: a live Hokuyo scanner over Ethernet (source = \"hokuyo\").",
    settings: &[
        set(
            "addr",
            "",
            Range::words("HOST:PORT that resolves"),
            "The scanner's address (--addr).",
        ),
        set(
            "frames",
            "scans",
            Range::ANY,
            "Scans to publish before stopping; 0 = until stopped.",
        ),
        set(
            "frame_id",
            "",
            Range::ANY,
            "frame_id of the published scans.",
        ),
        unset(
            "min_angle",
            "rad",
            Range::words("within the sensor's field"),
            "-1.5",
            "First bearing wanted; unset = the sensor's first step.",
        ),
        unset(
            "max_angle",
            "rad",
            Range::words("within the sensor's field"),
            "1.5",
            "Last bearing wanted; unset = the sensor's last step.",
        ),
        set(
            "cluster",
            "steps",
            Range::closed(1.0, 99.0),
            "Adjacent steps merged into one beam (the sensor reports the shortest).",
        ),
        set(
            "intensities",
            "",
            Range::ANY,
            "Ask for intensities as well as ranges.",
        ),
    ],
};

pub const GRID: Section = Section {
    table: "grid",
    about: "map-sink: the occupancy grid.",
    settings: &[set(
        "resolution",
        "m",
        Range::closed(0.005, 5.0),
        "Edge of a grid cell (--resolution).",
    )],
};

pub const RECORD: Section = Section {
    table: "record",
    about: "slam-record: every topic into OUT/run.mcap, for Foxglove.",
    settings: &[set("enabled", "", Range::ANY, "Record the run (--record).")],
};

pub const FOXGLOVE: Section = Section {
    table: "foxglove",
    about: "slam-view: the run served live to Foxglove over its WebSocket protocol.",
    settings: &[
        set(
            "enabled",
            "",
            Range::ANY,
            "Serve the run live (--foxglove).",
        ),
        set(
            "addr",
            "",
            Range::words("HOST:PORT that resolves, the port free"),
            "Where the live view listens (--foxglove ADDR); Foxglove connects to ws://ADDR.",
        ),
    ],
};
