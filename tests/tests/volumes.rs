//! Volume ray casting (issue 32): every structure's image bit for bit the dense marcher's — on
//! the Marschner–Lobb signal, a sparse field of blobs, and the MRI scan where installed, under
//! transfer functions from nothing empty to almost everything empty, from a camera outside the
//! volume and one inside it — with skipping really happening where space is empty, and a
//! transfer-function change giving what a rebuild with it gives. Transfer functions fitted to an
//! occupancy (the harness's sweep) make that fraction of voxels visible.

use glam::Vec3;
use kernels::volume::bricks::Bricks;
use kernels::volume::dense::Dense;
use kernels::volume::distfield::DistanceField;
use kernels::volume::ntree::NTree;
use kernels::volume::octree::MinMaxOctree;
use kernels::volume::{Histogram, TransferFunction, VOLUME_STRUCTURES, VolumeImage, VolumeStructure, render};
use scenes::{Camera, CameraSpec, Samples, Volume};

const SIZE: u32 = 72;

/// A sparse field: a few Gaussian blobs in an empty box (values 0..1).
fn blobs(n: u32) -> Volume {
    blobs_in([n; 3], [1.0; 3])
}

/// [`blobs`] in a box of `dims` voxels `spacing` apart (the blobs placed in the box's own unit
/// cube, so they stretch with it).
fn blobs_in(dims: [u32; 3], spacing: [f32; 3]) -> Volume {
    let centres = [Vec3::new(0.3, 0.4, 0.5), Vec3::new(0.7, 0.6, 0.3), Vec3::new(0.5, 0.2, 0.8)];
    let mut samples = Vec::with_capacity((dims[0] * dims[1] * dims[2]) as usize);
    let last = Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32) - 1.0;
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let p = Vec3::new(x as f32, y as f32, z as f32) / last;
                let v: f32 = centres.iter().map(|c| (-(p - *c).length_squared() / 0.004).exp()).sum();
                samples.push(if v < 1e-3 { 0.0 } else { v.min(1.0) });
            }
        }
    }
    Volume { name: "blobs".into(), dims, spacing, samples: Samples::F32(samples), source: "test".into() }
}

/// Three balls of 6 voxels' radius (value 200 inside, 0 elsewhere) in an empty `u8` box of `dims`
/// voxels `spacing` apart.
fn specks(dims: [u32; 3], spacing: [f32; 3]) -> Volume {
    let centres = [[0.2, 0.3, 0.4], [0.8, 0.7, 0.5], [0.5, 0.5, 0.9]]
        .map(|c: [f32; 3]| Vec3::new(c[0] * dims[0] as f32, c[1] * dims[1] as f32, c[2] * dims[2] as f32));
    let mut samples = Vec::with_capacity((dims[0] * dims[1] * dims[2]) as usize);
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let p = Vec3::new(x as f32, y as f32, z as f32);
                samples.push(if centres.iter().any(|c| p.distance(*c) <= 6.0) { 200u8 } else { 0 });
            }
        }
    }
    Volume { name: "specks".into(), dims, spacing, samples: Samples::U8(samples), source: "test".into() }
}

/// An N³-tree's builder ([`NTree::vdb`], [`NTree::tree64`]).
type TreeBuild = fn(&Volume, &TransferFunction) -> NTree;

/// Transfer functions over `volume`'s values `[lo, hi]`: nothing empty, a quarter, most, almost
/// all, all; one rising from the least value (regions of that value empty, all others visible); and
/// two fitted to 10 % and 1 % of the voxels visible, as the harness fits them.
fn transfer_functions(volume: &Volume) -> Vec<(&'static str, TransferFunction)> {
    let (lo, hi) = volume.value_range();
    let histogram = Histogram::of(volume);
    let fitted = |fraction: f64| TransferFunction::ramp_above(histogram.threshold_for(fraction), hi, 0.5);
    let everywhere =
        TransferFunction::new(vec![(lo, [0.2, 0.4, 0.9, 0.02]), (hi, [1.0, 1.0, 0.8, 0.3])]).expect("valid");
    let none = TransferFunction::new(vec![(lo, [1.0, 1.0, 1.0, 0.0])]).expect("valid");
    vec![
        ("nothing empty", everywhere),
        ("ramp 25 %", TransferFunction::ramp(lo, hi, 0.25, 0.6)),
        ("ramp 60 %", TransferFunction::ramp(lo, hi, 0.6, 0.9)),
        ("ramp 97 %", TransferFunction::ramp(lo, hi, 0.97, 1.0)),
        ("all transparent", none),
        ("from the least value", TransferFunction::ramp_above(lo, hi, 0.8)),
        ("visible 10 %", fitted(0.1)),
        ("visible 1 %", fitted(0.01)),
    ]
}

fn cameras(v: &Volume) -> Vec<(&'static str, Camera)> {
    let b = v.bounds();
    let outside = Camera::new(CameraSpec::canonical(b), SIZE, SIZE);
    let inside = CameraSpec { eye: b.center() + b.extent() * 0.05, target: b.max, up: Vec3::Y, vfov_deg: 70.0 };
    vec![("outside", outside), ("inside", Camera::new(inside, SIZE, SIZE))]
}

/// The largest difference of one channel between two images of the same size.
fn worst_channel(a: &VolumeImage, b: &VolumeImage) -> f32 {
    a.rgba.iter().zip(&b.rgba).flat_map(|(p, q)| (0..4).map(move |c| (p[c] - q[c]).abs())).fold(0.0, f32::max)
}

fn bits(image: &VolumeImage) -> Vec<[u32; 4]> {
    image.rgba.iter().map(|p| p.map(f32::to_bits)).collect()
}

fn check(volume: &Volume) {
    let step = volume.spacing[0] * 0.5;
    let mut skipped_somewhere = false;
    for (tf_name, tf) in transfer_functions(volume) {
        let bricks = Bricks::build(volume, &tf);
        let built: Vec<_> = VOLUME_STRUCTURES[1..].iter().map(|e| (e.name, (e.build)(volume, &tf))).collect();
        for (cam_name, camera) in cameras(volume) {
            let dense = render(&Dense, volume, &tf, &camera, step);
            for (structure, built) in &built {
                let image = render(built.as_ref(), volume, &tf, &camera, step);
                let differ = bits(&dense).iter().zip(bits(&image)).filter(|(a, b)| **a != *b).count();
                let what = format!("{} {tf_name} {cam_name}: {structure}", volume.name);
                assert_eq!(differ, 0, "{what}: {differ} pixels differ from the dense marcher's");
                assert!(image.samples <= dense.samples, "{what} takes more samples than the dense marcher");
                assert!(image.visits > 0, "{what}: no node visits counted");
                skipped_somewhere |= image.samples < dense.samples;
                if tf_name == "all transparent" {
                    // Every brick is skipped; a ray may still sample a span that ends a rounding
                    // error past the domain's far face (taken, never skipped: at most one sample).
                    assert!(image.samples <= u64::from(SIZE * SIZE) / 16, "{what}: {} samples taken", image.samples);
                }
            }
            assert_eq!(dense.visits, 0, "the dense marcher visits no nodes");
            if tf_name == "nothing empty" {
                assert_eq!(bricks.occupancy(), 1.0, "{}: nothing is empty", volume.name);
            }
            if tf_name == "all transparent" {
                assert!(
                    dense.rgba.iter().all(|p| *p == [0.0; 4]),
                    "{}: a transparent volume shows nothing",
                    volume.name
                );
            }
        }
    }
    assert!(skipped_somewhere, "{}: the bricks never skipped a sample", volume.name);
}

#[test]
fn bricks_give_the_dense_image_on_the_marschner_lobb_signal() {
    check(&scenes::load_volume("marschner-lobb@48", 1 << 30).expect("builds"));
}

#[test]
fn bricks_give_the_dense_image_on_sparse_blobs() {
    let v = blobs(80);
    check(&v);
    // Sparse indeed: at the 25 % ramp most bricks are empty and most samples are skipped.
    let (lo, hi) = v.value_range();
    let tf = TransferFunction::ramp(lo, hi, 0.25, 0.6);
    let bricks = Bricks::build(&v, &tf);
    assert!(bricks.occupancy() < 0.3, "{}", bricks.occupancy());
    let camera = Camera::new(CameraSpec::canonical(v.bounds()), SIZE, SIZE);
    let dense = render(&Dense, &v, &tf, &camera, 0.5);
    let fast = render(&bricks, &v, &tf, &camera, 0.5);
    assert!(fast.samples * 3 < dense.samples, "{} of {} samples", fast.samples, dense.samples);
}

#[test]
fn bricks_give_the_dense_image_on_a_particle_field() {
    check(&scenes::load_volume("particles@64:40", 1 << 30).expect("builds"));
}

#[test]
fn bricks_give_the_dense_image_on_the_mri_scan() {
    let required = std::env::var("ACCEL_BENCH_REQUIRE_VOLUMES").as_deref() == Ok("1");
    match scenes::load_volume("mri-ch2", 1 << 30) {
        Ok(v) => check(&v),
        Err(e) if !required => eprintln!("skipped: {e}"),
        Err(e) => panic!("{e}"),
    }
}

/// The N³-trees (`vdb`, `tree64`) where the vdb has several internal nodes (128³ voxels) along each
/// axis that has more than 128 voxels and the 64-tree three levels, with unequal spacings: the
/// dense image through every structure, and on a sparse field fewer node visits than the brick
/// map's (from outside, under half), since their empty nodes are stepped over whole.
#[test]
fn the_trees_step_over_empty_nodes_and_keep_the_dense_image() {
    let v = blobs_in([300, 40, 140], [1.0, 2.0, 0.5]);
    check(&v);
    let (lo, hi) = v.value_range();
    let ramp = TransferFunction::ramp(lo, hi, 0.25, 0.6);
    let vdb = NTree::vdb(&v, &ramp);
    assert_eq!(vdb.level_res(), [[3, 1, 2], [1, 1, 1]], "bricks {:?}", vdb.bricks.res);
    // The 64-tree over 38 × 5 × 18 bricks: 10 × 2 × 5, 3 × 1 × 2, 1 × 1 × 1.
    assert_eq!(NTree::tree64(&v, &ramp).level_res(), [[10, 2, 5], [3, 1, 2], [1, 1, 1]]);
    // Specks in a box of 4 × 3 × 3 internal nodes, most of them empty.
    let v = specks([400, 300, 260], [1.0, 1.5, 1.0]);
    check(&v);
    let tf = TransferFunction::ramp(0.0, 255.0, 0.25, 0.6);
    let vdb = NTree::vdb(&v, &tf);
    assert_eq!(vdb.level_res()[0], [4, 3, 3]);
    let tree64 = NTree::tree64(&v, &tf);
    let bricks = Bricks::build(&v, &tf);
    for (name, camera) in cameras(&v) {
        let through_bricks = render(&bricks, &v, &tf, &camera, 0.5);
        for (shape, tree) in [("vdb", &vdb), ("tree64", &tree64)] {
            let through = render(tree, &v, &tf, &camera, 0.5);
            assert_eq!(bits(&through_bricks), bits(&through), "{name} {shape}");
            assert_eq!(through_bricks.samples, through.samples, "{name} {shape}: the same non-empty bricks");
            // From outside most rays cross only empty nodes; from inside, the eye's own node and
            // its neighbour hold specks, so fewer are stepped over.
            let factor = if name == "outside" { 2 } else { 1 };
            assert!(
                through.visits * factor < through_bricks.visits,
                "{name}: {shape} visits {} nodes, the bricks {}",
                through.visits,
                through_bricks.visits
            );
        }
    }
}

/// The distance field leaps only empty bricks: through it every ray takes exactly the brick
/// map's samples (the same visible bricks, none skipped), on specks in a large empty box with
/// unequal spacings, from outside and inside, under several transfer functions — in far fewer
/// brick visits where space is empty; its distances are the brute-force Chebyshev distances
/// between bricks.
#[test]
fn the_distance_field_leaps_only_empty_bricks() {
    let v = specks([300, 220, 180], [1.0, 1.5, 0.75]);
    for (tf_name, tf) in transfer_functions(&v) {
        let bricks = Bricks::build(&v, &tf);
        let field = DistanceField::build(&v, &tf);
        assert_eq!(field.bytes(), bricks.bytes() + bricks.empty.len() as u64, "one byte a brick more");
        let [nx, ny, _] = bricks.res.map(i64::from);
        let at = |i: usize| [i as i64 % nx, i as i64 / nx % ny, i as i64 / (nx * ny)];
        let visible: Vec<[i64; 3]> = (0..bricks.empty.len()).filter(|&i| !bricks.empty[i]).map(at).collect();
        for (i, &d) in field.distance.iter().enumerate() {
            let c = at(i);
            let nearest = visible.iter().map(|o| (0..3).map(|a| (c[a] - o[a]).abs()).max().unwrap_or(0)).min();
            assert_eq!(i64::from(d), nearest.map_or(255, |n| n.min(255)), "{tf_name}: brick {c:?}");
        }
        for (cam, camera) in cameras(&v) {
            let (a, b) = (render(&bricks, &v, &tf, &camera, 0.5), render(&field, &v, &tf, &camera, 0.5));
            assert_eq!(bits(&a), bits(&b), "{tf_name} {cam}: the brick map's image");
            assert_eq!(a.samples, b.samples, "{tf_name} {cam}: the brick map's samples");
            assert!(b.visits <= a.visits, "{tf_name} {cam}: {} visits against the bricks' {}", b.visits, a.visits);
            if tf_name == "ramp 25 %" && cam == "outside" {
                assert!(b.visits * 4 < a.visits, "few leaps: {} visits against the bricks' {}", b.visits, a.visits);
            }
        }
    }
}

/// A new transfer function re-derives emptiness from the stored ranges: the same bricks and
/// the same image as a build with it.
#[test]
fn a_transfer_function_change_equals_a_rebuild() {
    let v = blobs(64);
    let tfs = transfer_functions(&v);
    let camera = Camera::new(CameraSpec::canonical(v.bounds()), SIZE, SIZE);
    for (from, a) in &tfs {
        for (to, b) in &tfs {
            let mut changed = Bricks::build(&v, a);
            changed.set_transfer_function(b);
            let rebuilt = Bricks::build(&v, b);
            assert_eq!(changed.empty, rebuilt.empty, "{from} -> {to}");
            assert_eq!(bits(&render(&changed, &v, b, &camera, 0.5)), bits(&render(&rebuilt, &v, b, &camera, 0.5)));
            let mut tree = MinMaxOctree::build(&v, a);
            tree.set_transfer_function(b);
            let tree_rebuilt = MinMaxOctree::build(&v, b);
            let (one, two) = (render(&tree, &v, b, &camera, 0.5), render(&tree_rebuilt, &v, b, &camera, 0.5));
            assert_eq!((bits(&one), one.samples), (bits(&two), two.samples), "octree {from} -> {to}");
            for (shape, build) in [("vdb", NTree::vdb as TreeBuild), ("tree64", NTree::tree64)] {
                let mut tree = build(&v, a);
                tree.set_transfer_function(b);
                let rebuilt = build(&v, b);
                let (one, two) = (render(&tree, &v, b, &camera, 0.5), render(&rebuilt, &v, b, &camera, 0.5));
                assert_eq!(
                    (bits(&one), one.samples, one.visits),
                    (bits(&two), two.samples, two.visits),
                    "{shape} {from} -> {to}"
                );
            }
            let mut field = DistanceField::build(&v, a);
            field.set_transfer_function(b);
            let field_rebuilt = DistanceField::build(&v, b);
            assert_eq!(field.distance, field_rebuilt.distance, "distfield {from} -> {to}");
            let (one, two) = (render(&field, &v, b, &camera, 0.5), render(&field_rebuilt, &v, b, &camera, 0.5));
            assert_eq!((bits(&one), one.visits), (bits(&two), two.visits), "distfield {from} -> {to}");
        }
    }
}

#[test]
fn transfer_functions_interpolate_and_refuse_bad_points() {
    let tf = TransferFunction::new(vec![(0.0, [0.0, 0.0, 0.0, 0.0]), (10.0, [1.0, 0.5, 0.0, 0.8]), (20.0, [1.0; 4])])
        .expect("valid");
    assert_eq!(tf.eval(-5.0), [0.0; 4]);
    assert_eq!(tf.eval(5.0), [0.5, 0.25, 0.0, 0.4]);
    assert_eq!(tf.eval(25.0), [1.0; 4]);
    assert_eq!(tf.max_opacity(-3.0, 0.0), 0.0);
    assert_eq!(tf.max_opacity(2.0, 15.0), 0.9);
    assert!(tf.is_empty_over(-3.0, -1.0) && !tf.is_empty_over(-3.0, 0.01));
    // An interpolated value can pass its corners by an ulp: the emptiness test widens the range.
    assert!(!tf.is_empty_over(-1.0, -0.0) || tf.eval(f32::EPSILON)[3] == 0.0);
    for bad in
        [vec![], vec![(1.0, [0.0; 4]), (1.0, [0.0; 4])], vec![(f32::NAN, [0.0; 4])], vec![(0.0, [2.0, 0.0, 0.0, 0.0])]]
    {
        assert!(TransferFunction::new(bad.clone()).is_err(), "{bad:?}");
    }
}

/// The fit the harness sweeps with: on a field whose values are known, each fraction of voxels
/// above the threshold is the nearest one held, the threshold's own voxels are not visible, a
/// fraction of 1 makes every voxel visible, and a ramp starting at the background value leaves
/// the background's bricks empty (a constant range is not widened).
#[test]
fn transfer_functions_fitted_to_an_occupancy_show_that_fraction() {
    // 16³ voxels: value z (0..15) on layer z, so each value holds 1/16 of the voxels.
    let n = 16u32;
    let samples: Vec<u8> = (0..n * n * n).map(|i| (i / (n * n)) as u8).collect();
    let v = Volume {
        name: "layers".into(),
        dims: [n; 3],
        spacing: [1.0; 3],
        samples: Samples::U8(samples),
        source: "test".into(),
    };
    let h = Histogram::of(&v);
    for (fraction, threshold) in [(0.5, 7.0), (0.25, 11.0), (1.0 / 16.0, 14.0), (0.3, 10.0)] {
        assert_eq!(h.threshold_for(fraction), threshold, "{fraction}");
        let tf = TransferFunction::ramp_above(threshold, 15.0, 0.5);
        let shown = h.visible(&tf);
        assert_eq!(shown, h.above(threshold));
        assert_eq!(shown, (15.0 - threshold as f64) / 16.0, "{fraction}");
    }
    let all = TransferFunction::ramp_above(h.threshold_for(1.0), 15.0, 0.5);
    assert_eq!(h.visible(&all), 1.0);
    assert!(Bricks::build(&v, &all).occupancy() == 1.0);
    // The particle field's background is 0: a ramp from 0 leaves its empty bricks empty.
    let field = scenes::load_volume("particles@64:4", 1 << 30).expect("builds");
    let from_zero = TransferFunction::ramp_above(0.0, 255.0, 0.5);
    let occupancy = Bricks::build(&field, &from_zero).occupancy();
    assert!(occupancy > 0.0 && occupancy < 0.5, "{occupancy}");
    assert!(TransferFunction::ramp_above(0.0, 255.0, 0.5).is_empty_over(0.0, 0.0));
    assert!(!TransferFunction::ramp_above(0.0, 255.0, 0.5).is_empty_over(0.0, 1e-30));
}

#[test]
fn transfer_functions_parse_what_they_describe_and_refuse_bad_text() {
    let tf = TransferFunction::parse("40:0,0,0,0; 255:1,0.9,0.8,0.6").expect("parses");
    assert_eq!(tf.points(), &[(40.0, [0.0; 4]), (255.0, [1.0, 0.9, 0.8, 0.6])]);
    assert_eq!(TransferFunction::parse(&tf.describe()), Ok(tf));
    for bad in ["", "40", "40:1,1,1", "x:1,1,1,1", "40:1,1,1,2", "50:0,0,0,0;40:1,1,1,1", "40:1,1,1,1,1"] {
        let e = TransferFunction::parse(bad).expect_err(bad);
        assert!(!e.is_empty(), "{bad}");
    }
}

/// The WGSL kernel (dense marcher, brick walk, octree walk) against the CPU's images, on `u8`,
/// `u16` and `f32` sources under transfer functions from nothing empty to 1 % visible, from
/// outside and inside: every channel within 1e-5; the dense and brick walks with the CPU's samples
/// and brick visits, the octree's (its own spans) with no more samples than the dense marcher. On
/// a device that rounds as the CPU does (lavapipe), the images are bit for bit the same.
#[test]
fn the_gpu_kernel_gives_the_cpu_image() {
    use kernels::gpu::volume::{GpuVolume, render_volume};
    let Some(ctx) = kernels::gpu::context_for_tests("the_gpu_kernel_gives_the_cpu_image") else { return };
    let exact = ctx.adapter_info().is_software();
    let field = blobs(40);
    let wide = Volume {
        name: "blobs u16".into(),
        samples: Samples::U16((0..field.samples.len()).map(|i| (field.samples.get(i) * 60000.0) as u16).collect()),
        ..field.clone()
    };
    let sources = [
        field,
        wide,
        scenes::load_volume("particles@48:20", 1 << 30).expect("builds"),
        scenes::load_volume("marschner-lobb@33", 1 << 30).expect("builds"),
        // Several of the vdb's internal nodes along x, some of them empty.
        specks([300, 150, 140], [1.0, 1.5, 1.0]),
    ];
    let opts = kernels::gpu::DispatchOptions { warmup: 0, reps: 1, ..Default::default() };
    for volume in &sources {
        let step = volume.spacing[0] * 0.5;
        for (tf_name, tf) in transfer_functions(volume).into_iter().filter(|(n, _)| !n.starts_with("ramp 60")) {
            let bricks = Bricks::build(volume, &tf);
            let octree = MinMaxOctree::build(volume, &tf);
            let vdb = NTree::vdb(volume, &tf);
            let tree64 = NTree::tree64(volume, &tf);
            let field = DistanceField::build(volume, &tf);
            for (cam_name, camera) in cameras(volume) {
                let dense = render(&Dense, volume, &tf, &camera, step);
                for (name, walk, cpu) in [
                    ("dense", GpuVolume::Dense, dense.clone()),
                    ("bricks", GpuVolume::Bricks(&bricks), render(&bricks, volume, &tf, &camera, step)),
                    ("octree", GpuVolume::Octree(&octree), render(&octree, volume, &tf, &camera, step)),
                    ("vdb", GpuVolume::Tree(&vdb), render(&vdb, volume, &tf, &camera, step)),
                    ("tree64", GpuVolume::Tree(&tree64), render(&tree64, volume, &tf, &camera, step)),
                    ("distfield", GpuVolume::DistanceField(&field), render(&field, volume, &tf, &camera, step)),
                ] {
                    let what = format!("{} {tf_name} {cam_name} {name}", volume.name);
                    let gpu =
                        render_volume(ctx, &kernels::volume::Sampler::new(volume), &walk, &tf, &camera, step, &opts)
                            .expect(&what)
                            .image;
                    let worst = worst_channel(&cpu, &gpu);
                    assert!(worst <= 1e-5, "{what}: a channel differs by {worst}");
                    if name == "octree" || name == "vdb" || name == "tree64" {
                        // The trees' GPU walk cuts its own spans (a descent per span).
                        assert!(gpu.samples <= dense.samples && gpu.visits > 0, "{what}");
                    } else {
                        assert_eq!((gpu.samples, gpu.visits), (cpu.samples, cpu.visits), "{what}");
                    }
                    if exact {
                        assert_eq!(bits(&gpu), bits(&cpu), "{what}: lavapipe rounds as the CPU does");
                    }
                }
            }
        }
    }
}

/// The samples' memory orders (`volume.order`, issue 43): Morton (by `pdep` where the CPU has it,
/// and by byte tables), 4³ and 8³ tiles. Every voxel reads back its row-major value, every stored
/// sample outside the volume is padding (zero), and every structure's image, samples and visits
/// equal the row-major ones bit for bit, on volumes of odd sizes in all three sample types.
#[test]
fn every_voxel_order_reads_the_same_samples_and_gives_the_same_images() {
    use kernels::volume::order::{VoxelOrder, VoxelStore};
    use kernels::volume::{Sampler, render_with};
    use structures::voxel::morton::Morton;
    let field = blobs_in([37, 20, 29], [1.0, 1.25, 0.75]);
    let wide = Volume {
        samples: Samples::U16((0..field.samples.len()).map(|i| (field.samples.get(i) * 60000.0) as u16).collect()),
        ..field.clone()
    };
    let sources = [
        field,
        wide,
        specks([45, 33, 70], [1.0; 3]),
        scenes::load_volume("marschner-lobb@33", 1 << 30).expect("builds"),
    ];
    let orders = [
        (VoxelOrder::Morton, Morton::detect()),
        (VoxelOrder::Morton, Morton::table()),
        (VoxelOrder::Tiles { shift: 2 }, Morton::detect()),
        (VoxelOrder::Tiles { shift: 3 }, Morton::detect()),
    ];
    for volume in &sources {
        let step = volume.spacing[0] * 0.5;
        for (order, encoder) in orders {
            let store = VoxelStore::new(volume, order, encoder).expect("fits");
            let what = format!("{} {} {}", volume.name, order.name(), encoder.name());
            let d = volume.dims;
            let mut taken = vec![false; store.padded_len()];
            for z in 0..d[2] {
                for y in 0..d[1] {
                    for x in 0..d[0] {
                        let i = store.index(x, y, z);
                        assert!(!std::mem::replace(&mut taken[i], true), "{what}: ({x}, {y}, {z}) shares index {i}");
                        assert_eq!(
                            store.value(x, y, z).to_bits(),
                            volume.value(x, y, z).to_bits(),
                            "{what} ({x}, {y}, {z})"
                        );
                    }
                }
            }
            let padding = taken.iter().enumerate().filter(|(_, t)| !**t).map(|(i, _)| i);
            assert!(padding.clone().all(|i| store.samples().get(i) == 0.0), "{what}: padding is zero");
            assert!(store.padded_len() as u64 >= volume.voxel_count());
            assert_eq!(store.padded_len() as u64, order.padded_len(d), "{what}: the budget's padded size");
            let sampler = Sampler::over(volume, store);
            for (tf_name, tf) in transfer_functions(volume).into_iter().step_by(3) {
                for e in VOLUME_STRUCTURES {
                    let built = (e.build)(volume, &tf);
                    for (cam_name, camera) in cameras(volume) {
                        let linear = render(built.as_ref(), volume, &tf, &camera, step);
                        let ordered = render_with(built.as_ref(), &sampler, &tf, &camera, step);
                        let case = format!("{what} {tf_name} {cam_name} {}", e.name);
                        assert_eq!(bits(&ordered), bits(&linear), "{case}: image");
                        assert_eq!((ordered.samples, ordered.visits), (linear.samples, linear.visits), "{case}");
                    }
                }
            }
        }
    }
    assert!(VoxelStore::new(&blobs(3), VoxelOrder::parse("tile8").expect("a name"), Morton::table()).is_ok());
    assert!(VoxelOrder::parse("hilbert").is_err());
}

/// The GPU kernel's addressing in every memory order (volume.wgsl's `voxel_index`): the dense
/// marcher and the brick walk give the CPU's image in each.
#[test]
fn the_gpu_kernel_reads_every_voxel_order() {
    use kernels::gpu::volume::{GpuVolume, render_volume};
    use kernels::volume::Sampler;
    use kernels::volume::order::{VoxelOrder, VoxelStore};
    use structures::voxel::morton::Morton;
    let Some(ctx) = kernels::gpu::context_for_tests("volumes::the_gpu_kernel_reads_every_voxel_order") else {
        return;
    };
    let exact = ctx.adapter_info().name.contains("llvmpipe");
    let opts = kernels::gpu::DispatchOptions { warmup: 0, reps: 1, ..Default::default() };
    for volume in [blobs_in([37, 20, 29], [1.0, 1.25, 0.75]), specks([45, 33, 70], [1.0; 3])] {
        let step = volume.spacing[0] * 0.5;
        let tf = transfer_functions(&volume).remove(6).1;
        let bricks = Bricks::build(&volume, &tf);
        let camera = cameras(&volume).remove(0).1;
        let cpu = render(&bricks, &volume, &tf, &camera, step);
        for order in
            [VoxelOrder::Linear, VoxelOrder::Morton, VoxelOrder::Tiles { shift: 2 }, VoxelOrder::Tiles { shift: 3 }]
        {
            let sampler = Sampler::over(&volume, VoxelStore::new(&volume, order, Morton::detect()).expect("fits"));
            for (name, walk) in [("dense", GpuVolume::Dense), ("bricks", GpuVolume::Bricks(&bricks))] {
                let what = format!("{} {} {name}", volume.name, order.name());
                let gpu = render_volume(ctx, &sampler, &walk, &tf, &camera, step, &opts).expect(&what).image;
                let worst = worst_channel(&cpu, &gpu);
                assert!(worst <= 1e-5, "{what}: a channel differs by {worst}");
                if exact {
                    assert_eq!(bits(&gpu), bits(&cpu), "{what}: lavapipe rounds as the CPU does");
                }
            }
        }
    }
}
