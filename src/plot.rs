//! Error against time, log-log, one line per variant and a peer's points for scale: the plot `ppm-vk
//! compare` draws. SVG, with its text as SVG text: no font is needed to write it (the viewer brings one).

use std::path::Path;

use anyhow::{anyhow, bail, Context as _, Result};
use plotters::prelude::*;

/// The variants' colours: Okabe and Ito's, which colour-blind readers tell apart (their yellow left out:
/// too faint on white).
const COLOURS: [RGBColor; 7] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(86, 180, 233),
    RGBColor(230, 159, 0),
    RGBColor(0, 0, 0),
];

/// One line: its name and (seconds, error) points.
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

/// A point of another renderer's, drawn as a marker (no line): (seconds, error, label).
#[derive(Clone, Debug, PartialEq)]
pub struct PeerPoint {
    pub seconds: f64,
    pub error: f64,
    pub label: String,
}

/// Reads a peer's points: one `seconds,error[,label]` line each (the label defaults to "peer"); blank
/// lines and lines starting with `#` are skipped. Errors name the file and line.
pub fn read_peer(path: &Path) -> Result<Vec<PeerPoint>> {
    // Bounded, and a regular file only (a FIFO would block for ever).
    let bytes = ppm_vk_engine::scene::read_bounded_bytes(path, ppm_vk_engine::scene::MAX_SCENE_BYTES, "peer file")?;
    let text = String::from_utf8(bytes).with_context(|| format!("reading the peer file {}", path.display()))?;
    let mut points = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let at = || format!("{}:{}", path.display(), i + 1);
        let fields: Vec<&str> = line.splitn(3, ',').map(str::trim).collect();
        if fields.len() < 2 {
            bail!("{}: expected `seconds,error[,label]`, got {line:?}", at());
        }
        let number = |s: &str, what: &str| -> Result<f64> {
            match s.parse::<f64>() {
                Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
                _ => bail!("{}: {what} must be a positive number (log axes), got {s:?}", at()),
            }
        };
        let label = fields
            .get(2)
            .filter(|l| !l.is_empty())
            .map_or("peer", |l| l)
            .to_string();
        points.push(PeerPoint {
            seconds: number(fields[0], "seconds")?,
            error: number(fields[1], "the error")?,
            label,
        });
    }
    if points.is_empty() {
        bail!("{}: no points (one `seconds,error[,label]` line each)", path.display());
    }
    Ok(points)
}

/// `v` with at most 3 significant digits and no trailing zeros: 0.001, 0.02, 0.5, 10, 200, 1e-5.
fn tick(v: f64) -> String {
    if v != 0.0 && !(1e-4..1e5).contains(&v.abs()) {
        return format!("{v:.0e}");
    }
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

/// Tick values in [lo, hi] for a log axis: 1, 2 and 5 times each power of ten, or only the powers where
/// that makes more than 12, or 1 to 9 times each where 1-2-5 makes fewer than 3; the ends of the range
/// (to two digits) where even that makes fewer than 2.
fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    // Through decimal text, so that 3e-2 is the f64 nearest 0.03 (3.0 * 1e-2 is not).
    let decimal = |m: u32, k: i32| format!("{m}e{k}").parse::<f64>().unwrap_or(f64::NAN);
    let candidates = |mantissas: &[u32]| -> Vec<f64> {
        let (k0, k1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
        (k0..=k1)
            .flat_map(|k| mantissas.iter().map(move |&m| decimal(m, k)))
            .filter(|v| (lo..=hi).contains(v))
            .collect()
    };
    let ticks = candidates(&[1, 2, 5]);
    if ticks.len() > 12 {
        return candidates(&[1]);
    }
    if ticks.len() >= 3 {
        return ticks;
    }
    let ticks = candidates(&[1, 2, 3, 4, 5, 6, 7, 8, 9]);
    if ticks.len() >= 2 {
        return ticks;
    }
    let two_digits = |v: f64| format!("{v:.1e}").parse::<f64>().unwrap_or(v);
    vec![two_digits(lo), two_digits(hi)]
}

fn err(e: impl std::fmt::Display) -> anyhow::Error {
    anyhow!("plot: {e}")
}

/// Draws `series` (lines with a marker at each point) and `peer` (triangles) on log-log axes into an
/// SVG at `path`.
pub fn error_plot(path: &Path, title: &str, y_label: &str, series: &[Series], peer: &[PeerPoint]) -> Result<()> {
    let positive = |(t, e): &(f64, f64)| *t > 0.0 && *e > 0.0;
    let all: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .chain(peer.iter().map(|p| (p.seconds, p.error)))
        .filter(positive)
        .collect();
    if all.is_empty() {
        bail!("nothing to plot: no positive times and errors");
    }
    let (t0, t1) = all
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), (t, _)| (a.min(*t), b.max(*t)));
    let (e0, e1) = all
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), (_, e)| (a.min(*e), b.max(*e)));
    let root = SVGBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(20)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d(
            (t0 * 0.8..t1 * 1.25)
                .log_scale()
                .with_key_points(log_ticks(t0 * 0.8, t1 * 1.25)),
            (e0 * 0.7..e1 * 1.4)
                .log_scale()
                .with_key_points(log_ticks(e0 * 0.7, e1 * 1.4)),
        )
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("wall time (s), log scale")
        .y_desc(format!("{y_label}, log scale"))
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 16))
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .light_line_style(WHITE.mix(0.0))
        .bold_line_style(BLACK.mix(0.12))
        .draw()
        .map_err(err)?;
    for (i, s) in series.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()].to_rgba();
        let pts: Vec<(f64, f64)> = s.points.iter().copied().filter(positive).collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))
            .map_err(err)?
            .label(s.name.clone())
            // A filled box, not a line: each variant is one polyline in the SVG.
            .legend(move |(x, y)| Rectangle::new([(x, y - 3), (x + 20, y + 3)], colour.filled()));
        chart
            .draw_series(pts.iter().map(|p| Circle::new(*p, 3, colour.filled())))
            .map_err(err)?;
    }
    let mut labels: Vec<&str> = Vec::new();
    for p in peer {
        if !labels.contains(&p.label.as_str()) {
            labels.push(&p.label);
        }
    }
    for (i, label) in labels.iter().enumerate() {
        let shade = if i == 0 { BLACK.to_rgba() } else { BLACK.mix(0.5) };
        chart
            .draw_series(
                peer.iter()
                    .filter(|p| p.label == *label)
                    .map(|p| TriangleMarker::new((p.seconds, p.error), 7, shade.filled())),
            )
            .map_err(err)?
            .label(label.to_string())
            .legend(move |(x, y)| TriangleMarker::new((x + 10, y), 7, shade.filled()));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 15))
        .draw()
        .map_err(err)?;
    root.present()
        .map_err(err)
        .with_context(|| format!("writing {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_short() {
        assert_eq!(tick(10.0), "10");
        assert_eq!(tick(0.5), "0.5");
        assert_eq!(tick(0.001), "0.001");
        assert_eq!(tick(2e-5), "2e-5");
    }

    #[test]
    fn log_ticks_span_the_range() {
        assert_eq!(log_ticks(0.4, 70.0), vec![0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0]);
        assert_eq!(log_ticks(1e-6, 1.0), vec![1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0]);
        assert_eq!(log_ticks(0.011, 0.019), vec![0.011, 0.019]);
        assert_eq!(log_ticks(0.011, 0.035), vec![0.02, 0.03]);
    }
}
