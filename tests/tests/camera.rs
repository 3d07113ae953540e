//! The canonical camera of docs/design.md §3 and its corner rays.

use glam::Vec3;
use scenes::{Aabb, Camera, CameraSpec};

fn spec() -> CameraSpec {
    CameraSpec::canonical(Aabb::new(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(3.0, 2.0, 4.0)))
}

#[test]
fn canonical_camera_is_where_the_spec_puts_it() {
    let s = spec();
    let c = Vec3::new(1.0, 1.0, 3.0);
    let d = (16.0f32 + 4.0 + 4.0).sqrt();
    assert!((s.eye - (c + d * Vec3::new(0.55, 0.40, 0.85))).length() < 1e-5, "{:?}", s.eye);
    assert_eq!(s.target, c);
    assert_eq!(s.up, Vec3::Y);
    assert_eq!(s.vfov_deg, 45.0);
}

#[test]
fn centre_pixel_looks_at_the_target() {
    // Odd sizes have a centre pixel.
    let cam = Camera::new(spec(), 101, 51);
    let r = cam.ray(50, 25);
    let to_target = (spec().target - spec().eye).normalize();
    assert!(r.dir.dot(to_target) > 1.0 - 1e-6, "{:?}", r.dir);
    assert_eq!(r.origin, spec().eye);
}

#[test]
fn corner_rays_span_the_field_of_view() {
    let (w, h) = (64u32, 48u32);
    let cam = Camera::new(spec(), w, h);
    let s = spec();
    let forward = (s.target - s.eye).normalize();
    let right = forward.cross(s.up).normalize();
    let up = right.cross(forward);
    let half = (22.5f32).to_radians().tan();
    // Pixel centres sit half a pixel inside the image edge.
    let (u, v) = ((w as f32 - 1.0) / h as f32 * half, (h as f32 - 1.0) / h as f32 * half);
    for (x, y, su, sv) in [(0, 0, -1.0, 1.0), (w - 1, 0, 1.0, 1.0), (0, h - 1, -1.0, -1.0), (w - 1, h - 1, 1.0, -1.0)] {
        let d = cam.ray(x, y).dir;
        assert!((d.length() - 1.0).abs() < 1e-6);
        let local = Vec3::new(d.dot(right), d.dot(up), d.dot(forward));
        // Projected onto the image plane at unit distance.
        let (pu, pv) = (local.x / local.z, local.y / local.z);
        assert!(
            (pu - su * u).abs() < 1e-5 && (pv - sv * v).abs() < 1e-5,
            "pixel ({x},{y}): ({pu}, {pv}) vs ({}, {})",
            su * u,
            sv * v
        );
    }
    // Vertical field of view: top and bottom edges of the image (not pixel centres) at ±22.5°.
    let top_edge = (h as f32 / 2.0) / h as f32 * 2.0 * half;
    assert!((top_edge.atan().to_degrees() - 22.5).abs() < 1e-4);
}
