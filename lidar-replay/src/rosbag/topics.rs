//! Which of a bag's topics are replayed: the LaserScan topic and the odometry's source,
//! given by the options or the only one of its type, and refusals that list the topics.

use super::messages::{LASER_SCAN, ODOMETRY, TF_MESSAGE};
use super::metadata::Topic;
use super::options::{BagOptions, OdometryFrom};
use super::storage::Channel;

/// The topic of static transforms, and of the others.
pub const TF_STATIC_TOPIC: &str = "/tf_static";
pub const TF_TOPIC: &str = "/tf";

/// Where the odometry of a replay comes from, once chosen.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum OdometryStream {
    /// An Odometry topic.
    Topic(String),
    /// `/tf`, odom frame to base frame.
    Tf,
}

/// `/scan (sensor_msgs/msg/LaserScan), /odom (nav_msgs/msg/Odometry)`.
pub(super) fn list_topics(topics: &[Topic]) -> String {
    if topics.is_empty() {
        return "none".into();
    }
    topics
        .iter()
        .map(|topic| format!("{} ({})", topic.name, topic.type_name))
        .collect::<Vec<_>>()
        .join(", ")
}

/// One topic per name, in the order first declared.
pub(super) fn topics_of(channels: &[Channel]) -> Vec<Topic> {
    let mut topics: Vec<Topic> = Vec::new();
    for channel in channels {
        if !topics.iter().any(|topic| topic.name == channel.topic) {
            topics.push(Topic {
                name: channel.topic.clone(),
                type_name: channel.type_name.clone(),
                messages: None,
            });
        }
    }
    topics
}

/// The scan and odometry topics of a bag with `topics`. `Err` says why they cannot be
/// chosen, the scan topic's problem first.
pub(super) fn choose(
    topics: &[Topic],
    options: &BagOptions,
) -> Result<(String, Option<OdometryStream>), String> {
    let scan_topic = choose_scan_topic(topics, options)?;
    Ok((scan_topic, choose_odometry(topics, options)?))
}

fn choose_scan_topic(topics: &[Topic], options: &BagOptions) -> Result<String, String> {
    choose_topic(
        topics,
        LASER_SCAN,
        options.scan_topic.as_deref(),
        "--scan-topic",
    )?
    .ok_or_else(|| {
        format!(
            "the bag has no {LASER_SCAN} topic to replay; its topics: {}",
            list_topics(topics)
        )
    })
}

/// The odometry `options.odometry` asks for; `Auto` takes the Odometry topic over `/tf`.
fn choose_odometry(
    topics: &[Topic],
    options: &BagOptions,
) -> Result<Option<OdometryStream>, String> {
    let has_tf = topics
        .iter()
        .any(|topic| topic.name == TF_TOPIC && topic.type_name == TF_MESSAGE);
    let odometry_topic = || {
        choose_topic(
            topics,
            ODOMETRY,
            options.odometry_topic.as_deref(),
            "--odom-topic",
        )
    };
    if let (OdometryFrom::Tf, Some(topic)) = (options.odometry, &options.odometry_topic) {
        return Err(format!(
            "--odom-topic {topic} names a {ODOMETRY} topic, but --odom-source tf reads the \
             odometry from {TF_TOPIC}: give one or the other"
        ));
    }
    match options.odometry {
        OdometryFrom::Odom => {
            let topic = odometry_topic()?.ok_or_else(|| {
                format!(
                    "--odom-source odom: the bag has no {ODOMETRY} topic; its topics: {}",
                    list_topics(topics)
                )
            })?;
            Ok(Some(OdometryStream::Topic(topic)))
        }
        OdometryFrom::Tf if has_tf => Ok(Some(OdometryStream::Tf)),
        OdometryFrom::Tf => Err(format!(
            "--odom-source tf: the bag has no {TF_TOPIC} topic of {TF_MESSAGE}; its topics: {}",
            list_topics(topics)
        )),
        OdometryFrom::Auto => Ok(match odometry_topic()? {
            Some(topic) => Some(OdometryStream::Topic(topic)),
            None if has_tf => Some(OdometryStream::Tf),
            None => None,
        }),
    }
}

/// The topic of `type_name` named `given` (by the option `option`), or the only one of
/// that type. `Err` says why none can be chosen, listing the bag's topics.
fn choose_topic(
    topics: &[Topic],
    type_name: &str,
    given: Option<&str>,
    option: &str,
) -> Result<Option<String>, String> {
    if let Some(name) = given {
        return given_topic(topics, type_name, name, option).map(Some);
    }
    let of_type: Vec<&Topic> = topics
        .iter()
        .filter(|topic| topic.type_name == type_name)
        .collect();
    match of_type[..] {
        [] => Ok(None),
        [only] => Ok(Some(only.name.clone())),
        _ => Err(format!(
            "the bag has {} {type_name} topics ({}): choose one with {option}",
            of_type.len(),
            of_type
                .iter()
                .map(|topic| topic.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        )),
    }
}

/// The topic `name`, if the bag has it and it is of `type_name`.
fn given_topic(
    topics: &[Topic],
    type_name: &str,
    name: &str,
    option: &str,
) -> Result<String, String> {
    match topics.iter().find(|topic| topic.name == name) {
        Some(topic) if topic.type_name == type_name => Ok(name.to_owned()),
        Some(topic) => Err(format!(
            "{name} ({option}) is {}, not {type_name}; the bag's topics: {}",
            topic.type_name,
            list_topics(topics)
        )),
        None => Err(format!(
            "the bag has no topic {name} ({option}); its topics: {}",
            list_topics(topics)
        )),
    }
}
