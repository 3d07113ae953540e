//! What the reports say about GPU rows and skipped renders, as plain text both report writers
//! wrap: the adapters a run used, and per scene one note per GPU row (upload, bindings, timer,
//! pre-pass) and per skipped render.

use crate::schema::{Case, Results};

/// Each adapter (with its driver) that GPU rows name, in first-seen order.
pub fn adapters(results: &Results) -> Vec<String> {
    let mut seen: Vec<String> = Vec::new();
    for gpu in results.cases.iter().flat_map(|c| &c.render).filter_map(|r| r.gpu.as_ref()) {
        let line = gpu.describe();
        if !seen.contains(&line) {
            seen.push(line);
        }
    }
    seen
}

/// One line per GPU row and per skipped render of `cases`.
pub fn notes(cases: &[&Case]) -> Vec<String> {
    let mut lines = Vec::new();
    for case in cases {
        let label = case.label();
        for r in &case.render {
            let Some(g) = &r.gpu else { continue };
            let prepass = g.prepass.as_ref().map_or(String::new(), |p| format!(", pre-pass {:.2} ms", p.ms_median));
            lines.push(format!(
                "{label} gpu/{}: {} — {} {}; kernel timed by {}{prepass}; upload {:.1} ms of {:.2} MiB \
                 ({:.2} MiB structure in {} binding{})",
                r.workload,
                g.adapter,
                g.driver,
                g.driver_info,
                g.timer,
                g.upload_ms,
                mib(g.upload_bytes),
                mib(g.structure_bytes),
                g.bindings,
                if g.bindings == 1 { "" } else { "s" }
            ));
        }
        for s in &case.skipped {
            lines.push(format!("{label} {}/{}: skipped, {}", s.backend, s.workload, s.reason));
        }
    }
    lines
}

fn mib(bytes: u64) -> f64 {
    bytes as f64 / (1u64 << 20) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::schema::{GpuStats, RenderStats, SkippedRender};

    #[test]
    fn notes_name_adapter_driver_and_skips() {
        let gpu = GpuStats {
            adapter: "llvmpipe".into(),
            driver: "llvmpipe".into(),
            driver_info: "Mesa 22.3.6".into(),
            api: "vulkan".into(),
            device_type: "Cpu".into(),
            timer: "timestamp-query".into(),
            upload_ms: 1.5,
            upload_bytes: 3 << 20,
            structure_bytes: 1 << 20,
            bindings: 3,
            prepass: None,
        };
        let row =
            RenderStats { backend: "gpu".into(), workload: "primary".into(), gpu: Some(gpu), ..Default::default() };
        let skip =
            SkippedRender { backend: "gpu".into(), workload: "shadow".into(), reason: "primary rays only".into() };
        let case = Case { structure: "org".into(), render: vec![row], skipped: vec![skip], ..Case::default() };
        let results = Results { cases: vec![case.clone(), case.clone()], ..Results::default() };
        assert_eq!(adapters(&results), ["llvmpipe — llvmpipe Mesa 22.3.6 (vulkan, Cpu)"]);
        let lines = notes(&[&case]);
        assert_eq!(lines.len(), 2);
        assert!(lines[0].starts_with("org gpu/primary: llvmpipe — llvmpipe Mesa 22.3.6"), "{}", lines[0]);
        assert!(lines[0].contains("upload 1.5 ms of 3.00 MiB (1.00 MiB structure in 3 bindings)"), "{}", lines[0]);
        assert_eq!(lines[1], "org gpu/shadow: skipped, primary rays only");
    }
}
