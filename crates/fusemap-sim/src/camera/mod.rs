//! The semantic RGB-D camera of the scenario (design document §2.2, §3.4): per frame a
//! class-label image, an aligned depth image and `sensor_msgs/CameraInfo`, rendered from a
//! 2.5D version of the hall ([`render`]) and spoilt the way real ones are:
//!
//! - depth noise σ = k·d² (Khoshelham & Elberink 2012), no depth beyond `max_depth_m`;
//! - salt noise on labels (a segmentation network's scattered wrong pixels);
//! - glass labelled `glass` but returning either its own depth or, by transmission, the
//!   depth of what lies behind it;
//! - a backlight effect: facing the windows, a share of the floor pixels is labelled as
//!   an obstacle class in smooth, drifting blobs while their depth stays the floor's;
//! - a clock offset: stamps are `true time + time_offset_s`.
//!
//! Class ids are the default class table's (see [`CLASS_NAMES`]).

mod config;
mod render;
#[cfg(test)]
mod tests;

pub use config::{optical_rotation, BacklightConfig, CameraConfig, DepthEncoding, LabelEncoding, MAX_CAMERA_BYTES};

use crate::messages::{SimCameraInfo, SimImage, SimMessage, SimStaticTransform};
use crate::path::Trajectory;
use crate::person::PersonConfig;
use crate::world::{Caster, WorldObject};
use fusemap_core::geometry::{normalize_angle, Point2, Pose2};
use fusemap_core::sim::SplitMix64;
use fusemap_core::time::Stamp;
use fusemap_io::log::ros2::msgs::geometry_msgs::{Transform, TransformStamped};
use fusemap_io::log::ros2::msgs::sensor_msgs::{CameraInfo, Image};
use fusemap_io::log::ros2::msgs::std_msgs::Header;
use render::{Frame, Renderer};

/// Class id of unlabelled pixels.
pub const CLASS_UNLABELED: u16 = 0;
/// Class id of the floor.
pub const CLASS_FLOOR: u16 = 1;
/// Class id of walls.
pub const CLASS_WALL: u16 = 2;
/// Class id of glass.
pub const CLASS_GLASS: u16 = 3;
/// Class id of pillars.
pub const CLASS_PILLAR: u16 = 4;
/// Class id of machines.
pub const CLASS_MACHINE: u16 = 5;
/// Class id of people.
pub const CLASS_PERSON: u16 = 6;
/// Class id of the ceiling (what a ray sees above every wall).
pub const CLASS_CEILING: u16 = 7;
/// The default class table's names, indexed by class id.
pub const CLASS_NAMES: [&str; 8] = ["unlabeled", "floor", "wall", "glass", "pillar", "machine", "person", "ceiling"];

/// The default class table's colours (RGB), indexed by class id.
pub const CLASS_COLORS: [[u8; 3]; 8] = [
    [0, 0, 0],
    [170, 170, 170],
    [90, 90, 200],
    [80, 200, 230],
    [230, 150, 40],
    [60, 170, 60],
    [230, 40, 40],
    [255, 255, 255],
];

/// The class id of a class name of the default table.
pub fn class_id(name: &str) -> Option<u16> {
    CLASS_NAMES.iter().position(|n| *n == name).map(|i| i as u16)
}

/// Most backlit floor points [`CameraTruth::backlit_floor_points`] keeps: a uniform
/// sample without replacement of all of them, taken as the points with the smallest hash
/// keys (bottom-k sampling, Cohen & Kaplan 2007), which merges across threads.
pub const MAX_BACKLIT_POINTS: usize = 20_000;

/// What the camera really did, for scoring a semantic map.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CameraTruth {
    /// Per frame: the true time it shows and the stamp it was published with.
    pub stamps: Vec<(Stamp, Stamp)>,
    /// Map-frame floor points of pixels the backlight mislabelled, within `max_depth_m`
    /// (a uniform sample of at most [`MAX_BACKLIT_POINTS`]).
    pub backlit_floor_points: Vec<Point2>,
    /// Frames in which the camera faced the windows.
    pub backlit_frames: u64,
    /// Pixels the backlight mislabelled, over the run.
    pub backlit_pixels: u64,
    /// Pixels given a random label by the salt noise.
    pub salt_pixels: u64,
    /// Pixels whose true label is `person`, over the run.
    pub person_pixels: u64,
}

/// One noisy frame.
#[derive(Clone, Debug, Default)]
pub(crate) struct NoisyFrame {
    /// Labels after the backlight and salt noise.
    pub labels: Vec<u16>,
    /// Depth after noise, metres (NaN: none).
    pub depth: Vec<f32>,
    /// The true frame.
    pub truth: Frame,
    /// Pixels the backlight relabelled.
    pub backlit: Vec<usize>,
    /// Whether the camera faced the windows.
    pub facing_window: bool,
    /// Pixels the salt noise relabelled.
    pub salted: u64,
}

/// The camera with its random streams.
pub(crate) struct CameraSim<'a> {
    cfg: &'a CameraConfig,
    renderer: Renderer<'a>,
    rng: SplitMix64,
    noise_seed: u64,
    blob_seed: u64,
    backlight_class: u16,
    blobs: render::BlobField,
    values: Vec<f32>,
}

impl<'a> CameraSim<'a> {
    pub fn new(cfg: &'a CameraConfig, objects: &[WorldObject], caster: &'a Caster, seed: u64) -> Self {
        let mut seeds = SplitMix64::new(seed);
        let noise_seed = seeds.next_u64();
        let blob_seed = seeds.next_u64();
        Self {
            cfg,
            renderer: Renderer::new(cfg, objects, caster),
            rng: SplitMix64::new(noise_seed),
            noise_seed,
            blob_seed,
            backlight_class: class_id(&cfg.backlight.class).unwrap_or(CLASS_WALL),
            blobs: render::BlobField::new(cfg.width as usize, cfg.height as usize, cfg.backlight.blob_scale_px),
            values: Vec::new(),
        }
    }

    pub fn renderer(&self) -> &Renderer<'a> {
        &self.renderer
    }

    /// Renders the frame of true time `t` (seconds since the start) from `pose`. Each
    /// frame draws its noise from its own stream, seeded by its time, so frames can be
    /// rendered in any order and on any thread with the same result.
    pub fn frame(&mut self, t: f64, pose: Pose2, person: Option<(Point2, f64, f64)>, out: &mut NoisyFrame) {
        let cfg = self.cfg;
        self.rng = SplitMix64::new(self.noise_seed ^ t.to_bits().wrapping_mul(0x9E37_79B9_7F4A_7C15));
        self.renderer.render(pose, person, &mut self.rng, &mut out.truth);
        out.labels.clear();
        out.labels.extend_from_slice(&out.truth.labels);
        out.backlit.clear();
        let b = &cfg.backlight;
        let heading = pose.theta + self.renderer.axis_heading;
        out.facing_window = b.enabled
            && normalize_angle(heading - b.window_yaw_deg.to_radians()).abs() <= b.half_angle_deg.to_radians();
        if out.facing_window && b.floor_share > 0.0 {
            // The field over the floor pixels, thresholded at its (1 − share) quantile so
            // exactly the share is relabelled; the field is smooth in u, v and t, so the
            // blobs are too.
            self.blobs.field_at(self.blob_seed, t / b.blob_period_s);
            let w = cfg.width as usize;
            self.values.clear();
            self.values.extend(
                out.truth.floor.iter().enumerate().filter(|(_, &f)| f).map(|(i, _)| self.blobs.value(i % w, i / w)),
            );
            let m = (b.floor_share * self.values.len() as f64).round() as usize;
            if m > 0 {
                let mut sorted = self.values.clone();
                let (_, &mut threshold, _) = sorted.select_nth_unstable_by(m - 1, |x, y| y.total_cmp(x));
                let mut left = m;
                let floor_pixels = out.truth.floor.iter().enumerate().filter(|(_, &f)| f).map(|(i, _)| i);
                for (i, &v) in floor_pixels.zip(&self.values) {
                    if left > 0 && v >= threshold {
                        out.backlit.push(i);
                        out.labels[i] = self.backlight_class;
                        left -= 1;
                    }
                }
            }
        }
        // Depth noise σ = k d²; Marsaglia's polar method gives two normals per accepted
        // pair of uniforms without trigonometry (Marsaglia & Bray 1964).
        out.depth.clear();
        let mut spare: Option<f64> = None;
        for &d in &out.truth.depth {
            let d = f64::from(d);
            if d.is_finite() && d <= cfg.max_depth_m {
                let g = match spare.take() {
                    Some(g) => g,
                    None => {
                        let (x, y, r2) = loop {
                            let (x, y) = (2.0 * self.rng.next_f64() - 1.0, 2.0 * self.rng.next_f64() - 1.0);
                            let r2 = x * x + y * y;
                            if r2 > 0.0 && r2 < 1.0 {
                                break (x, y, r2);
                            }
                        };
                        let f = (-2.0 * r2.ln() / r2).sqrt();
                        spare = Some(y * f);
                        x * f
                    }
                };
                out.depth.push((d + cfg.depth_sigma_k * d * d * g) as f32);
            } else {
                out.depth.push(f32::NAN);
            }
        }
        self.salt(out);
    }

    /// Salt: a share `label_noise_probability` of the labels set to random classes. The
    /// gaps between salted pixels are geometric (one draw per salted pixel instead of one
    /// per pixel).
    fn salt(&mut self, out: &mut NoisyFrame) {
        let p = self.cfg.label_noise_probability;
        out.salted = 0;
        if p > 0.0 {
            let mut i = 0usize;
            loop {
                let gap = if p >= 1.0 { 0.0 } else { ((1.0 - self.rng.next_f64()).ln() / (1.0 - p).ln()).floor() };
                if gap >= out.labels.len() as f64 {
                    break;
                }
                i += gap as usize;
                if i >= out.labels.len() {
                    break;
                }
                out.labels[i] = 1 + (self.rng.next_u64() % 6) as u16;
                out.salted += 1;
                i += 1;
            }
        }
    }
}

/// The published image bytes of labels.
pub(crate) fn encode_labels(labels: &[u16], enc: LabelEncoding) -> Vec<u8> {
    match enc {
        LabelEncoding::Mono8 => labels.iter().map(|&l| l.min(255) as u8).collect(),
        LabelEncoding::Mono16 => labels.iter().flat_map(|l| l.to_le_bytes()).collect(),
    }
}

/// The published image bytes of depths (NaN: none; `16UC1` writes 0 for none and
/// saturates at 65.535 m).
pub(crate) fn encode_depth(depth: &[f32], enc: DepthEncoding) -> Vec<u8> {
    match enc {
        DepthEncoding::Float32Metres => depth.iter().flat_map(|d| d.to_le_bytes()).collect(),
        DepthEncoding::U16Millimetres => depth
            .iter()
            .flat_map(|&d| {
                let mm =
                    if d.is_finite() && d > 0.0 { (f64::from(d) * 1000.0).round().min(65_535.0) as u16 } else { 0 };
                mm.to_le_bytes()
            })
            .collect(),
    }
}

/// The static transform `base_link → camera_optical` of a camera `cfg`, stamped `start`.
pub(crate) fn mount_message(cfg: &CameraConfig, start: Stamp, base_link: &str, frame_id: &str) -> SimStaticTransform {
    let p = cfg.base_from_optical();
    let transform = Transform { translation: p.translation.into(), rotation: p.rotation.into() };
    SimStaticTransform::new(
        "/tf_static",
        TransformStamped { header: Header::new(start, base_link), child_frame_id: frame_id.into(), transform },
    )
}

/// The camera's messages over the run (label, depth and info per frame, and its
/// `/tf_static` mount) and what it truly did.
pub(crate) struct CameraRun<'a> {
    pub cfg: &'a CameraConfig,
    pub frame_id: &'a str,
    pub objects: &'a [WorldObject],
    pub caster: &'a Caster,
    pub person: &'a PersonConfig,
    pub traj: &'a Trajectory,
    pub start: Stamp,
}

impl CameraRun<'_> {
    /// Every frame of the run, handed to `emit` in time order as it is rendered. Frames
    /// are rendered a chunk at a time, split over the machine's cores (frames are
    /// independent: each has its own noise stream), and the next chunk is rendered while
    /// `emit` takes the last: a run holds two chunks of images, not the whole recording,
    /// and writing them overlaps the rendering. The frames are the same whatever the
    /// chunks and the cores.
    pub fn stream(&self, seed: u64, emit: &mut dyn FnMut(SimMessage)) -> CameraTruth {
        let mut frames = 0u64;
        while frames as f64 / self.cfg.rate_hz <= self.traj.duration() {
            frames += 1;
        }
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).clamp(1, 4) as u64;
        let chunk = threads * FRAMES_PER_THREAD_AND_CHUNK;
        let mut truth = CameraTruth::default();
        let mut sample = Vec::new();
        let mut take = |parts: Vec<Part>, emit: &mut dyn FnMut(SimMessage)| {
            for p in parts {
                p.messages.into_iter().for_each(&mut *emit);
                truth.stamps.extend(p.truth.stamps);
                truth.backlit_frames += p.truth.backlit_frames;
                truth.backlit_pixels += p.truth.backlit_pixels;
                truth.salt_pixels += p.truth.salt_pixels;
                truth.person_pixels += p.truth.person_pixels;
                sample.extend(p.sample);
                bottom_k(&mut sample, MAX_BACKLIT_POINTS);
            }
        };
        let mut rendered: Vec<Part> = Vec::new();
        for first in (0..frames).step_by(chunk as usize) {
            let last = (first + chunk).min(frames);
            let per_thread = (last - first).div_ceil(threads).max(1);
            rendered = std::thread::scope(|scope| {
                let handles: Vec<_> = (0..threads)
                    .map(|k| {
                        let range = (first + k * per_thread).min(last)..(first + (k + 1) * per_thread).min(last);
                        scope.spawn(move || self.simulate_frames(seed, range))
                    })
                    .collect();
                take(std::mem::take(&mut rendered), emit);
                handles.into_iter().map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e))).collect()
            });
        }
        take(rendered, emit);
        sample.sort_unstable_by_key(|s| s.0);
        truth.backlit_floor_points = sample.into_iter().map(|s| s.1).collect();
        truth
    }

    /// The frames `range` (frame `n` shows true time `n / rate_hz`).
    fn simulate_frames(&self, seed: u64, range: std::ops::Range<u64>) -> Part {
        let cfg = self.cfg;
        let mut part = Part::default();
        let mut sim = CameraSim::new(cfg, self.objects, self.caster, seed);
        let sample_seed = SplitMix64::new(seed ^ 0x5EED_BAC1_1175_0000).next_u64();
        let mut threshold = u64::MAX;
        let mut frame = NoisyFrame::default();
        for n in range {
            let t = n as f64 / cfg.rate_hz;
            let pose = self.traj.pose_at(t);
            let person = self.person.position_at(t).map(|p| (p, self.person.radius_m, self.person.height_m));
            sim.frame(t, pose, person, &mut frame);
            let true_stamp = Stamp(self.start.0 + (t * 1e9).round() as i64);
            let stamp = Stamp(self.start.0 + ((t + cfg.time_offset_s) * 1e9).round() as i64);
            let truth = &mut part.truth;
            truth.stamps.push((true_stamp, stamp));
            truth.backlit_frames += u64::from(frame.facing_window);
            truth.backlit_pixels += frame.backlit.len() as u64;
            truth.person_pixels += frame.truth.labels.iter().filter(|&&l| l == CLASS_PERSON).count() as u64;
            truth.salt_pixels += frame.salted;
            // A bottom-k sample (the points with the smallest hash keys) is uniform, and
            // the same whichever thread saw which frame.
            let c = sim.renderer().centre_in_map(pose);
            for &i in &frame.backlit {
                let key = SplitMix64::new(sample_seed ^ (n << 24) ^ i as u64).next_u64();
                let s = f64::from(frame.truth.floor_depth[i]);
                if key >= threshold || s.is_nan() || s > cfg.max_depth_m {
                    continue;
                }
                let d = sim.renderer().ray_in_map(pose, i);
                part.sample.push((key, Point2::new(c[0] + s * d[0], c[1] + s * d[1])));
                if part.sample.len() >= 2 * MAX_BACKLIT_POINTS {
                    threshold = bottom_k(&mut part.sample, MAX_BACKLIT_POINTS);
                }
            }
            self.frame_messages(&frame, stamp, &mut part.messages);
        }
        part
    }

    /// The label image, the depth image and the camera info of one rendered frame.
    fn frame_messages(&self, frame: &NoisyFrame, stamp: Stamp, out: &mut Vec<SimMessage>) {
        let cfg = self.cfg;
        let k = cfg.k_matrix();
        let (w, h) = (cfg.width, cfg.height);
        let label_bytes = match cfg.label_encoding {
            LabelEncoding::Mono8 => 1,
            LabelEncoding::Mono16 => 2,
        };
        let depth_bytes = match cfg.depth_encoding {
            DepthEncoding::Float32Metres => 4,
            DepthEncoding::U16Millimetres => 2,
        };
        let image = |topic: &str, encoding: &str, bytes: u32, data: Vec<u8>| {
            SimImage::new(
                topic,
                Image {
                    header: Header::new(stamp, self.frame_id),
                    height: h,
                    width: w,
                    encoding: encoding.into(),
                    is_bigendian: 0,
                    step: w * bytes,
                    data: data.into(),
                },
            )
        };
        out.push(SimMessage::Image(image(
            &cfg.label_topic,
            cfg.label_encoding.as_str(),
            label_bytes,
            encode_labels(&frame.labels, cfg.label_encoding),
        )));
        out.push(SimMessage::Image(image(
            &cfg.depth_topic,
            cfg.depth_encoding.as_str(),
            depth_bytes,
            encode_depth(&frame.depth, cfg.depth_encoding),
        )));
        out.push(SimMessage::CameraInfo(Box::new(SimCameraInfo::new(
            &cfg.info_topic,
            CameraInfo {
                header: Header::new(stamp, self.frame_id),
                height: h,
                width: w,
                distortion_model: "plumb_bob".into(),
                d: vec![0.0; 5],
                k,
                r: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
                p: [k[0], 0.0, k[2], 0.0, 0.0, k[4], k[5], 0.0, 0.0, 0.0, 1.0, 0.0],
                ..CameraInfo::default()
            },
        ))));
    }
}

/// Frames each thread renders per chunk of [`CameraRun::stream`]: enough to keep the
/// threads' start-up small against the work (a frame takes milliseconds), few enough that
/// two chunks of images are a few tens of MiB.
pub(crate) const FRAMES_PER_THREAD_AND_CHUNK: u64 = 24;

/// What one thread rendered.
#[derive(Default)]
struct Part {
    messages: Vec<SimMessage>,
    truth: CameraTruth,
    /// Backlit floor points with their sampling keys.
    sample: Vec<(u64, Point2)>,
}

/// Keeps the `k` entries with the smallest keys (in no order) and returns the largest
/// key kept (`u64::MAX` while fewer than `k`): entries at or above it can be skipped.
fn bottom_k(v: &mut Vec<(u64, Point2)>, k: usize) -> u64 {
    if v.len() > k {
        v.select_nth_unstable_by_key(k - 1, |s| s.0);
        v.truncate(k);
    }
    if v.len() < k {
        return u64::MAX;
    }
    v.iter().map(|s| s.0).max().unwrap_or(u64::MAX)
}
