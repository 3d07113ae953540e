//! The `volume-ooc` preset end to end (issue 42): tiny sources — a generated particle field, the
//! Marschner–Lobb signal written to a store first — cast along a camera path through every page
//! table at a cache of a few bricks and at one that holds them all. Every frame checked against
//! the in-core dense marcher, the heap held against the cache plus the stated overhead, the
//! rounds a small cache costs; a damaged store is refused with where it is.

mod common;

use common::{harness, read_json, stderr, temp_dir};

#[test]
fn every_page_table_and_cache_size_gives_the_in_core_image_within_its_memory() {
    let out = temp_dir("ooc");
    let out_arg = out.to_string_lossy().into_owned();
    let scratch = temp_dir("ooc-scratch");
    let scratch_param = format!("volume.scratch={}", scratch.to_string_lossy());
    let args = [
        "run",
        "--preset",
        "volume-ooc",
        "--scenes",
        "particles@48:12,store:marschner-lobb@33",
        "--width",
        "40",
        "--height",
        "32",
        "--threads",
        "2",
        "--frames",
        "3",
        // 4 bricks' samples (9³ u8 a brick, 9³ f32), and far more than any source has.
        "--param",
        "volume.cache=2916,16M",
        "--param",
        "volume.brick=8",
        "--param",
        &scratch_param,
        "--out",
        &out_arg,
    ];
    let o = harness(&args);
    assert!(o.status.success(), "stderr: {}", stderr(&o));

    let results = read_json(&out.join("results.json"));
    assert_eq!(results["settings"]["workloads"][0], "volume-ooc");
    let cases = results["ooc"].as_array().expect("out-of-core cases");
    assert_eq!(cases.len(), 2 * 2 * 4, "two sources × two caches × four tables");
    for c in cases {
        let what = format!("{} {} {}", c["source"], c["table"], c["cache_bytes"]);
        assert_eq!(c["mismatched_pixels"], 0, "{what}: checked against the in-core dense marcher");
        let frames = c["frames"].as_array().expect("frames");
        assert_eq!(frames.len(), 3, "{what}");
        assert!(frames[0]["loads"].as_u64().is_some_and(|l| l > 0), "{what}: the first frame fills the cache");
        let (peak, cache, overhead) = (
            c["peak_bytes"].as_u64().unwrap(),
            c["cache_bytes"].as_u64().unwrap(),
            c["overhead_bytes"].as_u64().unwrap(),
        );
        assert!(peak > 0 && peak <= cache + overhead, "{what}: peak {peak} over {cache} + {overhead}");
        assert!(c["dense_ns_per_sample"].as_f64().is_some_and(|ns| ns > 0.0), "{what}");
        let slots = c["slots"].as_u64().unwrap();
        let working = frames.iter().map(|f| f["working_set"].as_u64().unwrap()).max().unwrap();
        if cache == 16 << 20 {
            // Everything fits: later frames load only what came into view, the warm frame nothing.
            assert!(slots >= c["bricks"].as_u64().unwrap(), "{what}");
            assert_eq!(c["warm"]["rounds"], 1, "{what}");
            assert_eq!(c["warm"]["loads"], 0, "{what}");
            assert_eq!(c["warm"]["misses"], 0, "{what}");
        } else {
            assert_eq!(slots, if c["source"] == "particles@48:12" { 4 } else { 1 }, "{what}");
            assert!(working > slots, "{what}: a frame needs more bricks than the cache holds");
            let rounds = frames.iter().map(|f| f["rounds"].as_u64().unwrap()).min().unwrap();
            assert!(rounds as f64 >= working as f64 / slots as f64, "{what}: at most a cache's bricks a round");
        }
        if c["table"] == "flat" {
            assert_eq!(c["table_bytes"].as_u64(), c["bricks"].as_u64().map(|b| 4 * b), "{what}: one u32 a brick");
        }
    }
    // Every table sees the same bricks and loads the same ones: they differ in translation only.
    for c in cases {
        let same = cases.iter().find(|d| d["source"] == c["source"] && d["cache_bytes"] == c["cache_bytes"]).unwrap();
        let loads = |c: &serde_json::Value| -> Vec<u64> {
            c["frames"].as_array().unwrap().iter().map(|f| f["loads"].as_u64().unwrap()).collect()
        };
        assert_eq!(loads(c), loads(same), "{} {}", c["source"], c["table"]);
    }
    let stored = cases.iter().find(|c| c["source"] == "store:marschner-lobb@33").unwrap();
    assert_eq!(stored["backing"], "file");
    assert!(stored["stored_bytes"].as_u64().is_some_and(|b| b > 0));
    let leftovers: Vec<_> = std::fs::read_dir(&*scratch).expect("scratch").collect();
    assert!(leftovers.is_empty(), "the store written for the run is removed after it: {leftovers:?}");

    let report = std::fs::read_to_string(out.join("report.md")).expect("report");
    assert!(report.contains("## Volumes larger than memory"), "{report}");
    assert!(report.contains("### Translation schemes side by side"));
    let html = std::fs::read_to_string(out.join("report.html")).expect("html");
    assert!(html.contains("ms a frame against the cache"));
}

#[test]
fn a_damaged_store_and_what_the_preset_cannot_do_are_refused() {
    let dir = temp_dir("ooc-refused");
    let broken = dir.join("broken.bricks");
    std::fs::write(&broken, b"ACBRICK1 but not a store").expect("write");
    let out = dir.join("run");
    let (broken_arg, out_arg) = (broken.to_string_lossy().into_owned(), out.to_string_lossy().into_owned());
    let o = harness(&["run", "--preset", "volume-ooc", "--scenes", &broken_arg, "--out", &out_arg]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("broken.bricks"), "names the file: {err}");
    let results = read_json(&out.join("results.json"));
    assert_eq!(results["skipped"][0]["kind"], "error");

    for (args, says) in [
        (&["--backend", "gpu"][..], "GPU path is not built"),
        (&["--structures", "bvh"][..], "not a page table"),
        (&["--param", "volume.cache=lots"][..], "volume.cache"),
        (&["--param", "volume.occupancy=10"][..], "not a parameter of the volume-ooc preset"),
        (&["--workload", "primary"][..], "takes no --workload"),
    ] {
        let mut all = vec!["run", "--preset", "volume-ooc", "--scenes", "particles@16:2"];
        all.extend_from_slice(args);
        let o = harness(&all);
        assert!(!o.status.success(), "{args:?}");
        assert!(stderr(&o).contains(says), "{args:?}: {}", stderr(&o));
    }
}
