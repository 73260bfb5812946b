//! Run reports: per pass the wall time, GPU time per stage, photons so far and (given a reference) the
//! error, plus what was run where. One schema (`ppm-vk-report/1`, documented in docs/report-format.md),
//! written as JSON or CSV, and the stage timeline in the Chrome trace-event format (Perfetto,
//! chrome://tracing).

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{bail, Context as _, Result};
use serde::{Deserialize, Serialize};

use crate::metrics::ErrorStats;
use crate::settings::Settings;
use crate::stats::{PassStats, ProbeReport};

pub const SCHEMA: &str = "ppm-vk-report/1";

/// Most bytes of a run report [`RunReport::load_json`] reads: 1 GiB.
pub const MAX_REPORT_BYTES: u64 = 1 << 30;

/// What was rendered, where, how.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunHeader {
    pub schema: String,
    /// `git describe` of the build, or "unknown".
    pub git_revision: String,
    pub device: String,
    pub device_kind: String,
    pub driver: String,
    pub scene_path: String,
    pub scene_name: String,
    /// SHA-256 of the scene file's bytes.
    pub scene_sha256: String,
    pub width: u32,
    pub height: u32,
    pub settings: Settings,
    /// GPU milliseconds of the first eye pass.
    pub ray_ms: f64,
    pub probe: Option<ProbeReport>,
}

/// One photon pass.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PassRecord {
    pub pass: u64,
    /// Seconds since the render started (renderer creation included), at the end of this pass.
    pub elapsed_s: f64,
    pub wall_ms: f64,
    pub photons_total: u64,
    pub records: u64,
    pub batches: u32,
    /// Photon and eye paths of the render so far cut at the depth backstops (`PassStats`).
    #[serde(default)]
    pub photon_paths_cut: u64,
    #[serde(default)]
    pub eye_paths_cut: u64,
    /// Photon fluxes held at the cap on smooth shading's correction so far (`PassStats`).
    #[serde(default)]
    pub photons_capped: u64,
    /// The largest live search radius after this pass, and the grid cell the next pass uses (`PassStats`).
    #[serde(default)]
    pub radius_max: f32,
    #[serde(default)]
    pub cell_size: f32,
    /// GPU milliseconds per stage, steps summed into their stage (`lookup/count` into `lookup`).
    pub stage_ms: BTreeMap<String, f64>,
    /// GPU start of each stage in milliseconds since the render's first timestamp, for traces.
    pub stage_start_ms: BTreeMap<String, f64>,
    /// Error against the reference, when one was given and evaluated after this pass.
    pub error: Option<ErrorStats>,
    pub region_errors: BTreeMap<String, ErrorStats>,
}

/// A whole run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunReport {
    pub header: RunHeader,
    pub passes: Vec<PassRecord>,
}

/// Stage names as reported: a step `a/b` counts toward `a`.
fn stage_of(name: &str) -> &str {
    name.split('/').next().unwrap_or(name)
}

impl PassRecord {
    /// `gpu_origin_ms`: the GPU time the render's trace starts at (see [`PassRecord::stage_start_ms`]).
    pub fn new(stats: &PassStats, elapsed_s: f64, gpu_origin_ms: f64) -> PassRecord {
        let mut stage_ms = BTreeMap::new();
        let mut stage_start_ms = BTreeMap::new();
        for s in &stats.stages {
            *stage_ms.entry(stage_of(s.name).to_string()).or_insert(0.0) += s.duration_ms;
            stage_start_ms
                .entry(stage_of(s.name).to_string())
                .or_insert(s.start_ms - gpu_origin_ms);
        }
        PassRecord {
            pass: stats.index,
            elapsed_s,
            wall_ms: stats.wall_ms,
            photons_total: stats.emitted_total,
            records: stats.records,
            batches: stats.batches,
            photon_paths_cut: stats.photon_paths_cut,
            eye_paths_cut: stats.eye_paths_cut,
            photons_capped: stats.photons_capped,
            radius_max: stats.radius_max,
            cell_size: stats.cell_size,
            stage_ms,
            stage_start_ms,
            error: None,
            region_errors: BTreeMap::new(),
        }
    }
}

impl RunReport {
    pub fn new(header: RunHeader) -> RunReport {
        RunReport {
            header,
            passes: Vec::new(),
        }
    }

    /// Writes JSON (`.json`) or CSV (`.csv`) by the extension of `path`.
    pub fn save(&self, path: &Path) -> Result<()> {
        let text = match path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .as_deref()
        {
            Some("json") => serde_json::to_string_pretty(self)?,
            Some("csv") => self.to_csv(),
            _ => bail!("report {}: the extension must be .json or .csv", path.display()),
        };
        std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))
    }

    /// Reads a JSON report of at most [`MAX_REPORT_BYTES`].
    pub fn load_json(path: &Path) -> Result<RunReport> {
        // Bounded, and a regular file only: a run report of 10^6 passes is a few hundred MB.
        let bytes = crate::scene::read_bounded_bytes(path, MAX_REPORT_BYTES, "run report")?;
        let text = String::from_utf8(bytes).with_context(|| format!("reading {}", path.display()))?;
        let report: RunReport = serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
        if report.header.schema != SCHEMA {
            bail!(
                "{}: schema {:?}, expected {SCHEMA:?}",
                path.display(),
                report.header.schema
            );
        }
        Ok(report)
    }

    /// One row per pass; stage columns are the union of the passes' stages.
    pub fn to_csv(&self) -> String {
        let mut stages: Vec<&String> = self.passes.iter().flat_map(|p| p.stage_ms.keys()).collect();
        stages.sort();
        stages.dedup();
        let mut out = String::from("pass,elapsed_s,wall_ms,photons_total,records");
        for s in &stages {
            out += &format!(",{s}_ms");
        }
        out += ",rmse,rel_mse,mean_bias\n";
        for p in &self.passes {
            out += &format!(
                "{},{:.6},{:.3},{},{}",
                p.pass, p.elapsed_s, p.wall_ms, p.photons_total, p.records
            );
            for s in &stages {
                out += &format!(",{:.3}", p.stage_ms.get(*s).copied().unwrap_or(0.0));
            }
            match &p.error {
                Some(e) => out += &format!(",{:.6},{:.6},{:.6}\n", e.rmse, e.rel_mse, e.mean_bias),
                None => out += ",,,\n",
            }
        }
        out
    }

    /// The Chrome trace-event JSON: on track "host", one span per pass (wall clock); on track "GPU",
    /// one span per stage (GPU timestamps).
    pub fn to_chrome_trace(&self) -> serde_json::Value {
        let mut events = vec![
            serde_json::json!({"name": "process_name", "ph": "M", "pid": 1, "args": {"name": "host"}}),
            serde_json::json!({"name": "process_name", "ph": "M", "pid": 2, "args": {"name": "GPU"}}),
        ];
        for p in &self.passes {
            let end_us = p.elapsed_s * 1e6;
            events.push(serde_json::json!({
                "name": format!("pass {}", p.pass), "ph": "X", "pid": 1, "tid": 1,
                "ts": end_us - p.wall_ms * 1e3, "dur": p.wall_ms * 1e3,
                "args": {"photons_total": p.photons_total, "records": p.records},
            }));
            for (stage, ms) in &p.stage_ms {
                let start = p.stage_start_ms.get(stage).copied().unwrap_or(0.0);
                events.push(serde_json::json!({
                    "name": stage, "ph": "X", "pid": 2, "tid": 1,
                    "ts": start * 1e3, "dur": ms * 1e3, "args": {"pass": p.pass},
                }));
            }
        }
        serde_json::json!({ "traceEvents": events, "displayTimeUnit": "ms" })
    }

    pub fn save_chrome_trace(&self, path: &Path) -> Result<()> {
        std::fs::write(path, serde_json::to_string(&self.to_chrome_trace())?)
            .with_context(|| format!("writing {}", path.display()))
    }
}

/// SHA-256 of a file, hex.
pub fn file_sha256(path: &Path) -> Result<String> {
    use sha2::Digest;
    let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    Ok(sha2::Sha256::digest(&bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use ppm_vk_device::ScopeTiming;

    fn sample() -> RunReport {
        let stats = PassStats {
            index: 1,
            photons: 1000,
            emitted_total: 1000,
            records: 2800,
            batches: 1,
            photon_paths_cut: 0,
            eye_paths_cut: 0,
            photons_capped: 0,
            radius_max: 0.01,
            cell_size: 0.02,
            wall_ms: 12.5,
            stages: vec![
                ScopeTiming {
                    name: "photon",
                    start_ms: 100.0,
                    duration_ms: 3.0,
                },
                ScopeTiming {
                    name: "lookup/count",
                    start_ms: 103.0,
                    duration_ms: 1.0,
                },
                ScopeTiming {
                    name: "lookup/scan",
                    start_ms: 104.0,
                    duration_ms: 0.5,
                },
                ScopeTiming {
                    name: "gather",
                    start_ms: 105.0,
                    duration_ms: 5.0,
                },
            ],
        };
        let mut p = PassRecord::new(&stats, 0.5, 100.0);
        p.error = Some(ErrorStats {
            rmse: 0.1,
            rel_mse: 0.01,
            mean_bias: -0.001,
            pixels: 16,
        });
        RunReport {
            header: RunHeader {
                schema: SCHEMA.into(),
                git_revision: "abc".into(),
                device: "llvmpipe".into(),
                device_kind: "CPU".into(),
                driver: "Mesa".into(),
                scene_path: "scenes/x.toml".into(),
                scene_name: "x".into(),
                scene_sha256: "00".into(),
                width: 4,
                height: 4,
                settings: Settings::default(),
                ray_ms: 1.0,
                probe: None,
            },
            passes: vec![p],
        }
    }

    #[test]
    fn steps_sum_into_their_stage() {
        let r = sample();
        assert_eq!(r.passes[0].stage_ms["lookup"], 1.5);
        assert_eq!(r.passes[0].stage_start_ms["lookup"], 3.0);
        assert_eq!(r.passes[0].stage_start_ms["photon"], 0.0);
    }

    #[test]
    fn json_round_trips() {
        let r = sample();
        let dir = std::env::temp_dir().join(format!("ppm-vk-report-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("r.json");
        r.save(&path).unwrap();
        assert_eq!(RunReport::load_json(&path).unwrap(), r);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn csv_has_a_row_per_pass_and_the_errors() {
        let csv = sample().to_csv();
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(
            lines[0],
            "pass,elapsed_s,wall_ms,photons_total,records,gather_ms,lookup_ms,photon_ms,rmse,rel_mse,mean_bias"
        );
        assert_eq!(
            lines[1],
            "1,0.500000,12.500,1000,2800,5.000,1.500,3.000,0.100000,0.010000,-0.001000"
        );
    }

    #[test]
    fn chrome_trace_has_pass_and_stage_spans() {
        let t = sample().to_chrome_trace();
        let events = t["traceEvents"].as_array().unwrap();
        let spans: Vec<&serde_json::Value> = events.iter().filter(|e| e["ph"] == "X").collect();
        assert_eq!(spans.len(), 1 + 3);
        let pass = spans.iter().find(|e| e["pid"] == 1).unwrap();
        assert_eq!(pass["dur"], 12500.0);
        assert_eq!(pass["ts"], 500000.0 - 12500.0);
    }

    #[test]
    fn wrong_extension_and_schema_are_errors() {
        assert!(sample().save(Path::new("/tmp/report.txt")).is_err());
        let mut r = sample();
        r.header.schema = "other/9".into();
        let path = std::env::temp_dir().join(format!("ppm-vk-report-schema-{}.json", std::process::id()));
        std::fs::write(&path, serde_json::to_string(&r).unwrap()).unwrap();
        assert!(RunReport::load_json(&path).is_err());
        std::fs::remove_file(&path).ok();
    }
}
