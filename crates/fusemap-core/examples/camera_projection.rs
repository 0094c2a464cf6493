//! How long the camera model takes to project one 640×480 label + depth frame, at stride
//! 4 and 1. A timing run, not a test:
//!
//! ```text
//! cargo run --release -p fusemap-core --example camera_projection
//! ```
//!
//! The frame: a Kinect-like pinhole (f = 525 px) 0.8 m up, pitched down 0.35 rad, looking
//! at a floor and a wall 4 m ahead, every pixel labelled and with depth.

use fusemap_core::geometry::Pose2;
use fusemap_core::measurement::SensorId;
use fusemap_core::sensor::camera::optical_mount;
use fusemap_core::sensor::{
    CameraModel, CameraObservation, CameraParams, ClassTable, DepthImage, LabelImage, Pinhole, PixelCounts,
};
use std::time::Instant;

fn main() {
    let (w, h) = (640u32, 480u32);
    let pinhole = Pinhole::new(w, h, 525.0, 525.0, 319.5, 239.5).expect("valid intrinsics");
    let (height, pitch) = (0.8f64, 0.35f64);
    let mount = optical_mount([0.1, 0.0, height], 0.0, pitch);
    let (mut labels, mut depth) = (Vec::with_capacity((w * h) as usize), Vec::with_capacity((w * h) as usize));
    for v in 0..h {
        for _u in 0..w {
            // Elevation of the row's ray below the optical axis, then the ray's depth along the
            // axis to the floor or to the wall at x = 4 m, whichever is nearer.
            let yn = (v as f64 + 0.5 - 239.5) / 525.0;
            let down = pitch + yn.atan();
            let to_floor = if down > 0.0 { height / down.sin() } else { f64::INFINITY };
            let to_wall = 3.9 / down.cos();
            let (label, range) = if to_floor < to_wall { (1, to_floor) } else { (2, to_wall) };
            labels.push(label);
            depth.push((range * yn.atan().cos()) as f32);
        }
    }
    let labels = LabelImage::new(w, h, labels).expect("sized");
    let depth = DepthImage::new(w, h, depth).expect("sized");
    for stride in [4u32, 1] {
        let params = CameraParams { stride, ..Default::default() };
        let build = Instant::now();
        let model = CameraModel::new(pinhole, mount, params, 0.05, ClassTable::production_default()).expect("valid");
        let build = build.elapsed();
        let mut out = CameraObservation::empty(SensorId(0));
        let mut counts = PixelCounts::default();
        let frames = if stride == 1 { 200 } else { 2000 };
        // One warm-up frame sizes the buffer.
        model.project(&labels, &depth, Pose2::new(1.0, 2.0, 0.3), &mut out, &mut counts).expect("fits");
        let start = Instant::now();
        for i in 0..frames {
            let pose = Pose2::new(1.0 + i as f64 * 1e-3, 2.0, 0.3);
            model.project(&labels, &depth, pose, &mut out, &mut counts).expect("fits");
        }
        let per_frame = start.elapsed().as_secs_f64() / frames as f64;
        let per_frame_pixels = counts.seen as f64 / (frames + 1) as f64;
        println!(
            "stride {stride}: {:.3} ms per 640x480 frame ({per_frame_pixels:.0} pixels looked at, {} used), \
             {:.1} M pixels/s; model built in {:.3} ms",
            per_frame * 1e3,
            out.points.len(),
            per_frame_pixels / per_frame / 1e6,
            build.as_secs_f64() * 1e3,
        );
    }
}
