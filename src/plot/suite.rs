//! Pictures of a whole suite: every failing layout over the mission (top-down), and the low-fidelity
//! prediction against the flown distance of every flight.

use std::fmt::Write as _;

use super::{Canvas, MARGIN_PX, SIZE_PX, esc};
use crate::model::{Arena, Obstacle, TestCase};

/// Colours the layouts cycle through.
const PALETTE: [&str; 8] = [
    "#c0392b", "#1f5fbf", "#2a9d3a", "#8e44ad", "#e67e22", "#16a085", "#7f8c8d", "#d35400",
];

/// Legend rows at most; the layouts beyond are drawn but listed as a count.
const MAX_LEGEND: usize = 12;

/// One layout of the suite: its label (e.g. `test_0: 0.42 m`) and its obstacles (Aerialist frame).
pub struct Layout {
    /// Shown in the legend and, shortened to its first word, on the obstacles.
    pub label: String,
    /// The obstacles.
    pub obstacles: Vec<Obstacle>,
}

/// Top-down SVG of `layouts` over `case`'s obstacle area and mission path (East right, North up, metres).
pub fn layouts_svg(case: &TestCase, layouts: &[Layout], title: &str) -> String {
    let arena = Arena::default();
    let mission: Vec<(f64, f64)> = (case.mission.flight_path().iter())
        .map(|p| (p.north_m, p.east_m))
        .collect();
    let footprints: Vec<Vec<[(f64, f64); 4]>> = (layouts.iter())
        .map(|l| {
            (l.obstacles.iter())
                .map(|o| o.footprint().corners().map(|c| (c.x, c.y)))
                .collect()
        })
        .collect();
    let mut pts = vec![(arena.x.min, arena.y.min), (arena.x.max, arena.y.max)];
    pts.extend(mission.iter().copied());
    pts.extend(footprints.iter().flatten().flatten().copied());
    let c = Canvas::new(square_bounds(&pts));
    let rows = layouts.len().min(MAX_LEGEND) + 2 + usize::from(layouts.len() > MAX_LEGEND);
    let mut s = header(SIZE_PX, SIZE_PX + 20.0 * rows as f64, title);
    c.grid(&mut s);
    super::obstacle_area(&c, &mut s, &arena);
    let _ = writeln!(
        s,
        r##"<polyline points="{}" fill="none" stroke="#333" stroke-width="2" stroke-dasharray="2 4"/>"##,
        c.poly(&mission)
    );
    for (k, (layout, boxes)) in layouts.iter().zip(&footprints).enumerate().rev() {
        let colour = PALETTE[k % PALETTE.len()];
        let name = layout.label.split(':').next().unwrap_or_default();
        for corners in boxes {
            let _ = writeln!(
                s,
                r#"<polygon points="{}" fill="{colour}" fill-opacity="0.15" stroke="{colour}" stroke-width="1.5"/>"#,
                c.poly(corners)
            );
            let (n, e) = corners
                .iter()
                .fold((0.0, 0.0), |a, p| (a.0 + p.0 / 4.0, a.1 + p.1 / 4.0));
            let (x, y) = c.px(n, e);
            let _ = writeln!(
                s,
                r#"<text x="{x:.1}" y="{y:.1}" text-anchor="middle" font-size="10" fill="{colour}">{}</text>"#,
                esc(name.trim_start_matches("test_"))
            );
        }
    }
    legend(&mut s, layouts);
    s.push_str("</svg>\n");
    s
}

/// One flight in the scatter: predicted and flown minimum distance (metres), and whether it is a test the
/// report wrote.
pub struct Point {
    /// The low-fidelity prediction.
    pub predicted_m: f64,
    /// The flown distance.
    pub flown_m: f64,
    /// Drawn filled (a written failing test's flight) or hollow.
    pub highlighted: bool,
}

/// Distances beyond this are drawn at the edge: the interesting part is the first metres.
const AXIS_MAX_M: f64 = 10.0;

/// SVG scatter of predicted (x) against flown (y) minimum distance, with the 1.5 m failure lines and the
/// diagonal where the prediction is exact.
pub fn scatter_svg(points: &[Point], threshold_m: f64, title: &str) -> String {
    let top = (points.iter())
        .flat_map(|p| [p.predicted_m, p.flown_m])
        .filter(|v| v.is_finite())
        .fold(2.0 * threshold_m, f64::max)
        .min(AXIS_MAX_M)
        .ceil();
    let plot = SIZE_PX - 2.0 * MARGIN_PX;
    let px = |v: f64| MARGIN_PX + v.clamp(0.0, top) / top * plot;
    let py = |v: f64| SIZE_PX - MARGIN_PX - v.clamp(0.0, top) / top * plot;
    let mut s = header(SIZE_PX, SIZE_PX + 40.0, title);
    let (x0, x1, y0, y1) = (px(0.0), px(top), py(0.0), py(top));
    let _ = writeln!(
        s,
        r##"<rect x="{x0:.1}" y="{y1:.1}" width="{:.1}" height="{:.1}" fill="none" stroke="#999"/>"##,
        x1 - x0,
        y0 - y1
    );
    for m in 0..=(top as usize) {
        let v = m as f64;
        let _ = writeln!(
            s,
            r##"<text x="{:.1}" y="{:.1}" text-anchor="middle" fill="#666">{m}</text><text x="{:.1}" y="{:.1}" text-anchor="end" fill="#666">{m}</text>"##,
            px(v),
            y0 + 16.0,
            x0 - 6.0,
            py(v) + 4.0
        );
    }
    let (tx, ty) = (px(threshold_m), py(threshold_m));
    let _ = writeln!(
        s,
        r##"<rect x="{x0:.1}" y="{ty:.1}" width="{:.1}" height="{:.1}" fill="#c0392b" fill-opacity="0.08"/>"##,
        x1 - x0,
        y0 - ty
    );
    let _ = writeln!(
        s,
        r##"<line x1="{tx:.1}" y1="{y0:.1}" x2="{tx:.1}" y2="{y1:.1}" stroke="#c0392b" stroke-dasharray="4 3"/><line x1="{x0:.1}" y1="{ty:.1}" x2="{x1:.1}" y2="{ty:.1}" stroke="#c0392b" stroke-dasharray="4 3"/>"##
    );
    let _ = writeln!(
        s,
        r##"<line x1="{x0:.1}" y1="{y0:.1}" x2="{x1:.1}" y2="{y1:.1}" stroke="#bbb"/>"##
    );
    for p in points
        .iter()
        .filter(|p| p.predicted_m.is_finite() && p.flown_m.is_finite())
    {
        let fill = if p.highlighted { "#c0392b" } else { "none" };
        let _ = writeln!(
            s,
            r##"<circle cx="{:.1}" cy="{:.1}" r="4" fill="{fill}" stroke="#7b241c"/>"##,
            px(p.predicted_m),
            py(p.flown_m)
        );
    }
    scatter_labels(&mut s, (x0, x1, y0, y1), top, threshold_m);
    s.push_str("</svg>\n");
    s
}

/// The layouts' legend below the picture: the path, the obstacle area, then each layout (at most
/// [`MAX_LEGEND`], the rest counted).
fn legend(s: &mut String, layouts: &[Layout]) {
    let mut legend: Vec<(String, String)> = vec![
        ("#333".into(), "mission path (dashed)".into()),
        ("#d9b24a".into(), "obstacle area".into()),
    ];
    legend.extend(
        (layouts.iter().enumerate().take(MAX_LEGEND))
            .map(|(k, l)| (PALETTE[k % PALETTE.len()].into(), l.label.clone())),
    );
    if layouts.len() > MAX_LEGEND {
        legend.push(("#999".into(), format!("and {} more", layouts.len() - MAX_LEGEND)));
    }
    for (k, (colour, text)) in legend.iter().enumerate() {
        let y = SIZE_PX + 5.0 + 20.0 * k as f64;
        let _ = writeln!(
            s,
            r#"<rect x="{MARGIN_PX}" y="{:.1}" width="20" height="10" fill="{colour}" fill-opacity="0.4" stroke="{colour}"/><text x="{:.1}" y="{:.1}">{}</text>"#,
            y - 5.0,
            MARGIN_PX + 30.0,
            y + 4.0,
            esc(text)
        );
    }
}

/// The scatter's axis titles and key, around the plot area `(x0, x1, y0, y1)` in pixels.
fn scatter_labels(s: &mut String, (x0, x1, y0, y1): (f64, f64, f64, f64), top: f64, threshold_m: f64) {
    let _ = writeln!(
        s,
        r##"<text x="{:.1}" y="{:.1}" text-anchor="middle">predicted minimum distance, m (beyond {top} m: at the edge)</text>"##,
        (x0 + x1) / 2.0,
        y0 + 34.0
    );
    let _ = writeln!(
        s,
        r##"<text x="12" y="{:.1}" transform="rotate(-90 12 {:.1})" text-anchor="middle">flown minimum distance, m</text>"##,
        (y0 + y1) / 2.0,
        (y0 + y1) / 2.0
    );
    let _ = writeln!(
        s,
        r##"<text x="{MARGIN_PX}" y="{:.1}">filled: a written failing test's flight; shaded: flown below {threshold_m} m; grey line: prediction exact</text>"##,
        SIZE_PX + 30.0
    );
}

fn header(w: f64, h: f64, title: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{MARGIN_PX}" y="20" font-size="14">{}</text>"#,
        esc(title)
    );
    s
}

/// (min north, max north, min east, max east) around `pts`, padded to a square.
fn square_bounds(pts: &[(f64, f64)]) -> (f64, f64, f64, f64) {
    let (mut n0, mut n1, mut e0, mut e1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(n, e) in pts.iter().filter(|(n, e)| n.is_finite() && e.is_finite()) {
        n0 = n0.min(n);
        n1 = n1.max(n);
        e0 = e0.min(e);
        e1 = e1.max(e);
    }
    let span = (n1 - n0).max(e1 - e0) + 4.0;
    let (cn, ce) = ((n0 + n1) / 2.0, (e0 + e1) / 2.0);
    (cn - span / 2.0, cn + span / 2.0, ce - span / 2.0, ce + span / 2.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn the_suite_picture_draws_every_layout_and_lists_them() {
        let case = TestCase::load(Path::new("missions/mission2.yaml")).unwrap();
        let layouts: Vec<Layout> = (0..14)
            .map(|k| Layout {
                label: format!("test_{k}: 0.{k} m"),
                obstacles: vec![
                    Obstacle::new(5.0, 5.0, 15.0, 10.0 + k as f64, 20.0, 0.0),
                    Obstacle::new(5.0, 5.0, 15.0, -10.0, 30.0, 0.0),
                ],
            })
            .collect();
        let svg = layouts_svg(&case, &layouts, "failing tests <2>");
        assert!(svg.starts_with("<svg") && svg.ends_with("</svg>\n"));
        assert_eq!(
            svg.matches(r#"fill-opacity="0.15""#).count(),
            28,
            "two boxes per layout"
        );
        assert!(svg.contains("test_11: 0.11 m") && !svg.contains("test_12: 0.12 m"));
        assert!(svg.contains("and 2 more") && svg.contains("failing tests &lt;2&gt;"));
    }

    #[test]
    fn the_scatter_clamps_far_flights_and_marks_written_tests() {
        let points = [
            Point {
                predicted_m: 0.5,
                flown_m: 1.0,
                highlighted: true,
            },
            Point {
                predicted_m: 30.0,
                flown_m: 2.0,
                highlighted: false,
            },
            Point {
                predicted_m: f64::NAN,
                flown_m: 2.0,
                highlighted: false,
            },
        ];
        let svg = scatter_svg(&points, 1.5, "predicted against flown");
        assert_eq!(svg.matches("<circle").count(), 2, "the NaN is left out");
        assert_eq!(svg.matches(r##"fill="#c0392b" stroke"##).count(), 1);
        assert!(svg.contains("beyond 10 m"));
        let empty = scatter_svg(&[], 1.5, "none");
        assert!(empty.contains("beyond 3 m") && !empty.contains("<circle"));
    }
}
