//! Error against time, log-log, one line per variant: the plot `ppm-vk compare` draws.

use std::path::Path;

use anyhow::{anyhow, bail, Context as _, Result};
use plotters::prelude::*;

/// Where Debian (fonts-dejavu-core), Fedora and Arch keep DejaVu Sans.
const FONT_PATHS: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu-sans-fonts/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
];

fn register_font() -> Result<()> {
    let path = FONT_PATHS.iter().find(|p| Path::new(p).exists()).ok_or_else(|| {
        anyhow!("no DejaVu Sans font for the plot's labels (looked in {}): `sudo apt-get install fonts-dejavu-core`", FONT_PATHS.join(", "))
    })?;
    let bytes: &'static [u8] = Box::leak(std::fs::read(path).with_context(|| format!("reading {path}"))?.into_boxed_slice());
    register_font_bytes(bytes)
}

fn register_font_bytes(bytes: &'static [u8]) -> Result<()> {
    plotters::style::register_font("sans-serif", FontStyle::Normal, bytes).map_err(|_| anyhow!("the font file is not a usable TrueType font"))
}

/// One line: its name and (seconds, error) points.
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

/// Draws `series` on log-log axes into a PNG at `path`.
pub fn error_plot(path: &Path, title: &str, y_label: &str, series: &[Series]) -> Result<()> {
    let points = || series.iter().flat_map(|s| s.points.iter()).filter(|(t, e)| *t > 0.0 && *e > 0.0);
    let (t0, t1) = points().fold((f64::MAX, f64::MIN), |(a, b), (t, _)| (a.min(*t), b.max(*t)));
    let (e0, e1) = points().fold((f64::MAX, f64::MIN), |(a, b), (_, e)| (a.min(*e), b.max(*e)));
    if t0 > t1 || e0 > e1 {
        bail!("nothing to plot: no positive times and errors");
    }
    register_font()?;
    let (w, h) = (900u32, 600u32);
    let mut buffer = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow!("plot: {e}"))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(72)
            .build_cartesian_2d((t0 * 0.9..t1 * 1.1).log_scale(), (e0 * 0.8..e1 * 1.25).log_scale())
            .map_err(|e| anyhow!("plot: {e}"))?;
        chart
            .configure_mesh()
            .x_desc("wall time (s)")
            .y_desc(y_label)
            .label_style(("sans-serif", 15))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .draw()
            .map_err(|e| anyhow!("plot: {e}"))?;
        for (i, s) in series.iter().enumerate() {
            let colour = Palette99::pick(i).to_rgba();
            let pts: Vec<(f64, f64)> = s.points.iter().copied().filter(|(t, e)| *t > 0.0 && *e > 0.0).collect();
            chart
                .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))
                .map_err(|e| anyhow!("plot: {e}"))?
                .label(s.name.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
            chart.draw_series(pts.iter().map(|p| Circle::new(*p, 3, colour.filled()))).map_err(|e| anyhow!("plot: {e}"))?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 15))
            .draw()
            .map_err(|e| anyhow!("plot: {e}"))?;
        root.present().map_err(|e| anyhow!("plot: {e}"))?;
    }
    let image = image::RgbImage::from_raw(w, h, buffer).ok_or_else(|| anyhow!("plot buffer size"))?;
    image.save(path).with_context(|| format!("writing {}", path.display()))
}
