//! The survey of a bag before anything is published (see the module's documentation):
//! its topics chosen, its first scan read, its static transforms gathered for the mount.

use std::path::Path;

use super::decode::{Decoded, Plan};
use super::error::BagError;
use super::info::BagInfo;
use super::locate::{Located, locate};
use super::messages::{LaserScan, TfMessage};
use super::metadata::Topic;
use super::mount::StaticTransforms;
use super::options::BagOptions;
use super::reader::BagReader;
use super::storage::{Channel, Damaged, RawMessage};
use super::stream::Messages;
use super::topics::{OdometryStream, TF_STATIC_TOPIC, choose, topics_of};
use crate::lines::StopFlag;

/// The first scan must come within this many messages; a bag without one is refused then
/// rather than read to its end.
pub const SNIFF_MESSAGES: u64 = 100_000;

/// Static transforms recorded up to this long (bag time) after the first scan still
/// place the laser.
pub const STATIC_LOOKAHEAD_NS: u64 = 2_000_000_000;

/// Surveys the bag at `path` (see the module's documentation) and opens it for replay.
pub fn open_bag_until(
    path: &Path,
    options: &BagOptions,
    stop: StopFlag,
) -> Result<(BagReader, BagInfo), BagError> {
    let info = survey(path, options, stop)?;
    Ok((BagReader::new(&info, options.reorder, stop), info))
}

/// [`open_bag_until`] without a stop: the survey alone, as slam-launch checks a bag before
/// it starts anything.
pub fn check_bag(path: &Path, options: &BagOptions) -> Result<BagInfo, BagError> {
    survey(path, options, crate::lines::never)
}

fn survey(path: &Path, options: &BagOptions, stop: StopFlag) -> Result<BagInfo, BagError> {
    let Located {
        storage,
        files,
        topics: declared,
    } = locate(path)?;
    let mut survey = Survey::new(path, options, declared)?;
    let mut messages = Messages::new(storage, files.clone());
    survey.read(&mut messages, stop)?;
    let (topics, scan_topic, odometry) = survey.choice()?;
    let scan = survey.first_scan(&scan_topic, messages.read())?;
    let scan_frame = scan.header.frame_id;
    let mount = survey
        .statics
        .mount(&options.base_frame, &scan_frame)
        .map_err(|cause| BagError::Mount {
            path: path.to_path_buf(),
            cause,
        })?;
    Ok(BagInfo {
        path: path.to_path_buf(),
        storage,
        files,
        topics,
        scan_topic,
        scan_frame,
        odometry,
        mount,
        base_frame: options.base_frame.clone(),
        odom_frame: options.odom_frame.clone(),
    })
}

/// What the survey has met so far.
struct Survey<'a> {
    path: &'a Path,
    options: &'a BagOptions,
    /// The topics the bag declares; `None`: only the channels met tell.
    declared: Option<Vec<Topic>>,
    /// The scan and odometry topics, once they can be chosen.
    chosen: Option<(String, Option<OdometryStream>)>,
    /// The channels met, one per topic, for a bag that declares no topics.
    seen: Vec<Channel>,
    statics: StaticTransforms,
    /// The first scan and its bag time.
    first_scan: Option<(LaserScan, u64)>,
    /// The first message that could not be used, told when no scan is found.
    first_problem: Option<String>,
}

impl<'a> Survey<'a> {
    /// With the topics known, chooses now (`Err` if it cannot); else the channels the
    /// survey meets choose.
    fn new(
        path: &'a Path,
        options: &'a BagOptions,
        declared: Option<Vec<Topic>>,
    ) -> Result<Self, BagError> {
        let mut survey = Self {
            path,
            options,
            declared,
            chosen: None,
            seen: Vec::new(),
            statics: StaticTransforms::default(),
            first_scan: None,
            first_problem: None,
        };
        if let Some(topics) = &survey.declared {
            let chosen = choose(topics, options).map_err(|reason| survey.topics_error(reason))?;
            survey.chosen = Some(chosen);
        }
        Ok(survey)
    }

    fn topics_error(&self, reason: String) -> BagError {
        BagError::Topics {
            path: self.path.to_path_buf(),
            reason,
        }
    }

    /// Reads messages until the first scan and the static transforms after it are in,
    /// [`SNIFF_MESSAGES`] pass without a scan, or the bag ends.
    fn read(&mut self, messages: &mut Messages, stop: StopFlag) -> Result<(), BagError> {
        while let Some(next) = messages.next() {
            if stop() {
                return Err(BagError::Stopped {
                    path: self.path.to_path_buf(),
                });
            }
            let message = match next {
                Ok(message) => message,
                Err(Damaged(cause)) if self.first_scan.is_none() => {
                    return Err(BagError::Damaged {
                        path: self.path.to_path_buf(),
                        messages: messages.read(),
                        cause,
                    });
                }
                // Cut later on: the replay reads up to there and reports it.
                Err(_) => break,
            };
            if !self.take(&message, messages.read()) {
                break;
            }
        }
        Ok(())
    }

    /// Takes in `message`, the `index`-th; whether to read on.
    fn take(&mut self, message: &RawMessage, index: u64) -> bool {
        self.meet(&message.channel);
        if message.channel.topic == TF_STATIC_TOPIC {
            self.add_statics(message);
        }
        match &self.first_scan {
            None => {
                self.try_first_scan(message, index);
                self.first_scan.is_some() || index < SNIFF_MESSAGES
            }
            Some((_, at)) => message.log_time_ns <= at.saturating_add(STATIC_LOOKAHEAD_NS),
        }
    }

    /// Notes the channel of a bag that declares no topics; until the first scan, a new
    /// topic chooses again.
    fn meet(&mut self, channel: &Channel) {
        if self.declared.is_some() || self.seen.iter().any(|c| c.topic == channel.topic) {
            return;
        }
        self.seen.push(channel.clone());
        if self.first_scan.is_none() {
            self.chosen = choose(&topics_of(&self.seen), self.options).ok();
        }
    }

    fn add_statics(&mut self, message: &RawMessage) {
        match TfMessage::decode(&message.data) {
            Ok(tf) => tf.transforms.into_iter().for_each(|t| self.statics.add(t)),
            Err(e) => {
                self.first_problem
                    .get_or_insert(format!("{TF_STATIC_TOPIC}: {e}"));
            }
        }
    }

    /// Takes `message` for the first scan if it is one on the scan topic chosen.
    fn try_first_scan(&mut self, message: &RawMessage, index: u64) {
        let Some((scan_topic, _)) = &self.chosen else {
            return;
        };
        if message.channel.topic != *scan_topic {
            return;
        }
        match Plan::scans_only(scan_topic, self.options).decode(index, message) {
            Ok(Decoded::Scan(scan)) => self.first_scan = Some((scan, message.log_time_ns)),
            Ok(_) => {}
            Err(e) => {
                self.first_problem.get_or_insert(e.to_string());
            }
        }
    }

    /// The bag's topics and the scan and odometry topics chosen: `Err` if none could be
    /// chosen among the topics only the survey saw, saying why.
    fn choice(&mut self) -> Result<(Vec<Topic>, String, Option<OdometryStream>), BagError> {
        let undeclared = self.declared.is_none();
        let topics = self
            .declared
            .take()
            .unwrap_or_else(|| topics_of(&self.seen));
        let (scan_topic, mut odometry) = match self.chosen.take() {
            Some(chosen) => chosen,
            None => choose(&topics, self.options).map_err(|reason| self.topics_error(reason))?,
        };
        // The odometry from every channel met, some after the first scan.
        if undeclared && let Ok((_, later)) = choose(&topics, self.options) {
            odometry = later;
        }
        Ok((topics, scan_topic, odometry))
    }

    /// The first scan, or why the bag has none to replay after `read` messages.
    fn first_scan(&mut self, scan_topic: &str, read: u64) -> Result<LaserScan, BagError> {
        if let Some((scan, _)) = self.first_scan.take() {
            return Ok(scan);
        }
        let within = if read >= SNIFF_MESSAGES {
            format!("in its first {SNIFF_MESSAGES} messages")
        } else {
            format!("in its {read} messages")
        };
        Err(BagError::NoScan {
            path: self.path.to_path_buf(),
            topic: scan_topic.to_owned(),
            within,
            problem: self
                .first_problem
                .take()
                .map(|p| format!(" (first problem: {p})"))
                .unwrap_or_default(),
        })
    }
}
