//! Top-down SVG plots of a test and its flights (simulated or flown), written by hand as text.
//!
//! The map shows the local ground frame with East to the right and North up (metres): the obstacle area, the
//! obstacles, the mission, any number of paths and the closest approach, with a legend.

use std::fmt::Write as _;

pub mod suite;

use crate::judge::ClosestApproach;
use crate::model::{Arena, TestCase, Trajectory};

/// How a path is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PathStyle {
    /// A low-fidelity simulation (blue).
    Simulated,
    /// A real (high-fidelity) flight (green).
    Flown,
    /// Anything else (grey, dashed).
    Other,
}

impl PathStyle {
    fn stroke(self) -> (&'static str, &'static str) {
        match self {
            Self::Simulated => ("#1f5fbf", ""),
            Self::Flown => ("#2a9d3a", ""),
            Self::Other => ("#777777", " stroke-dasharray=\"4 3\""),
        }
    }
}

struct PathLine {
    points: Vec<(f64, f64)>,
    style: PathStyle,
    label: String,
}

/// A plot under construction; points are `(north, east)` metres.
pub struct FlightPlot {
    arena: Arena,
    obstacles: Vec<[(f64, f64); 4]>,
    mission: Vec<(f64, f64)>,
    paths: Vec<PathLine>,
    closest: Option<ClosestApproach>,
    title: String,
}

const SIZE_PX: f64 = 720.0;
const MARGIN_PX: f64 = 40.0;

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

impl FlightPlot {
    /// A plot of `test`'s arena, obstacles and mission.
    pub fn new(test: &TestCase) -> Self {
        let obstacles = test
            .obstacles
            .iter()
            .map(|o| o.footprint().corners().map(|c| (c.x, c.y)))
            .collect();
        let mission = test
            .mission
            .flight_path()
            .iter()
            .map(|p| (p.north_m, p.east_m))
            .collect();
        Self {
            arena: Arena::default(),
            obstacles,
            mission,
            paths: Vec::new(),
            closest: None,
            title: test.path.display().to_string(),
        }
    }

    /// Adds a path (Aerialist frame: x North, y East).
    pub fn add_path(&mut self, trajectory: &Trajectory, style: PathStyle, label: &str) {
        self.paths.push(PathLine {
            points: trajectory.samples.iter().map(|s| (s.x, s.y)).collect(),
            style,
            label: label.to_string(),
        });
    }

    /// Marks the closest approach.
    pub fn mark_closest(&mut self, c: &ClosestApproach) {
        self.closest = Some(*c);
    }

    /// Sets the title (default: the test's path).
    pub fn set_title(&mut self, title: &str) {
        self.title = title.to_string();
    }

    /// Bounds (min north, max north, min east, max east) of everything drawn, padded to a square.
    fn bounds(&self) -> (f64, f64, f64, f64) {
        let mut pts: Vec<(f64, f64)> = vec![
            (self.arena.x.min, self.arena.y.min),
            (self.arena.x.max, self.arena.y.max),
        ];
        pts.extend(self.obstacles.iter().flatten());
        pts.extend(&self.mission);
        for p in &self.paths {
            pts.extend(p.points.iter().filter(|(n, e)| n.is_finite() && e.is_finite()));
        }
        let (mut n0, mut n1, mut e0, mut e1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for (n, e) in pts {
            n0 = n0.min(n);
            n1 = n1.max(n);
            e0 = e0.min(e);
            e1 = e1.max(e);
        }
        let span = (n1 - n0).max(e1 - e0) + 4.0;
        let (cn, ce) = ((n0 + n1) / 2.0, (e0 + e1) / 2.0);
        (cn - span / 2.0, cn + span / 2.0, ce - span / 2.0, ce + span / 2.0)
    }

    /// The SVG document.
    pub fn to_svg(&self) -> String {
        let c = Canvas::new(self.bounds());
        let legend_h = 20.0 * (3 + self.paths.len() + usize::from(self.closest.is_some())) as f64;
        let mut s = String::new();
        let _ = writeln!(
            s,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="12">"#,
            w = SIZE_PX,
            h = SIZE_PX + legend_h
        );
        let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
        let _ = writeln!(
            s,
            r#"<text x="{MARGIN_PX}" y="20" font-size="14">{}</text>"#,
            esc(&self.title)
        );
        c.grid(&mut s);
        self.write_obstacles(&c, &mut s);
        self.write_mission(&c, &mut s);
        self.write_paths(&c, &mut s);
        self.write_legend(&mut s);
        s.push_str("</svg>\n");
        s
    }

    /// The obstacle area and the obstacles, numbered.
    fn write_obstacles(&self, c: &Canvas, s: &mut String) {
        obstacle_area(c, s, &self.arena);
        for (k, o) in self.obstacles.iter().enumerate() {
            let _ = writeln!(
                s,
                r##"<polygon points="{}" fill="#c0392b" fill-opacity="0.55" stroke="#7b241c"/>"##,
                c.poly(o)
            );
            let (cn, ce) = o
                .iter()
                .fold((0.0, 0.0), |acc, p| (acc.0 + p.0 / 4.0, acc.1 + p.1 / 4.0));
            let (x, y) = c.px(cn, ce);
            let _ = writeln!(
                s,
                r#"<text x="{x:.1}" y="{y:.1}" text-anchor="middle" fill="white">{k}</text>"#
            );
        }
    }

    /// The mission's path and its numbered waypoints.
    fn write_mission(&self, c: &Canvas, s: &mut String) {
        let _ = writeln!(
            s,
            r##"<polyline points="{}" fill="none" stroke="#333" stroke-dasharray="2 4"/>"##,
            c.poly(&self.mission)
        );
        for (k, &(n, e)) in self.mission.iter().enumerate() {
            let (x, y) = c.px(n, e);
            let _ = writeln!(
                s,
                r##"<circle cx="{x:.1}" cy="{y:.1}" r="4" fill="#333"/><text x="{:.1}" y="{:.1}">{k}</text>"##,
                x + 6.0,
                y - 6.0
            );
        }
    }

    /// The paths, then the closest approach on top of them.
    fn write_paths(&self, c: &Canvas, s: &mut String) {
        for p in &self.paths {
            let (color, dash) = p.style.stroke();
            let _ = writeln!(
                s,
                r#"<polyline points="{}" fill="none" stroke="{color}" stroke-width="2"{dash}/>"#,
                c.poly(&p.points)
            );
        }
        if let Some(cl) = &self.closest {
            let (x, y) = c.px(cl.x, cl.y);
            let _ = writeln!(
                s,
                r##"<circle cx="{x:.1}" cy="{y:.1}" r="6" fill="none" stroke="#e67e22" stroke-width="2.5"/><text x="{:.1}" y="{:.1}" fill="#e67e22">{:.2} m</text>"##,
                x + 8.0,
                y + 4.0,
                cl.distance
            );
        }
    }

    /// Legend: one row of 20 px per entry below the map; each swatch is drawn about the row's centre line `y`.
    fn write_legend(&self, s: &mut String) {
        let x = MARGIN_PX;
        for (k, (swatch, text)) in self.legend_rows().iter().enumerate() {
            let y = SIZE_PX + 5.0 + 20.0 * k as f64;
            let swatch = swatch
                .replace("{x}", &format!("{x:.1}"))
                .replace("{x10}", &format!("{:.1}", x + 10.0))
                .replace("{x20}", &format!("{:.1}", x + 20.0))
                .replace("{y5}", &format!("{:.1}", y - 5.0))
                .replace("{y}", &format!("{y:.1}"));
            let _ = writeln!(
                s,
                r#"{swatch}<text x="{:.1}" y="{:.1}">{}</text>"#,
                x + 30.0,
                y + 4.0,
                esc(text)
            );
        }
    }

    /// (swatch template, text) per legend row; the template's `{x}`, `{y}`, ... are filled in per row.
    fn legend_rows(&self) -> Vec<(String, String)> {
        let mut rows: Vec<(String, String)> = vec![
            (
                r##"<rect x="{x}" y="{y5}" width="20" height="10" fill="#c0392b" fill-opacity="0.55"/>"##.into(),
                "obstacles".into(),
            ),
            (
                r##"<rect x="{x}" y="{y5}" width="20" height="10" fill="#fff8e0" stroke="#d9b24a"/>"##.into(),
                "obstacle area".into(),
            ),
            (
                r##"<line x1="{x}" y1="{y}" x2="{x20}" y2="{y}" stroke="#333" stroke-dasharray="2 4"/>"##.into(),
                "mission".into(),
            ),
        ];
        for p in &self.paths {
            let (color, dash) = p.style.stroke();
            rows.push((
                format!(
                    r#"<line x1="{{x}}" y1="{{y}}" x2="{{x20}}" y2="{{y}}" stroke="{color}" stroke-width="2"{dash}/>"#
                ),
                p.label.clone(),
            ));
        }
        if let Some(c) = &self.closest {
            rows.push((
                r##"<circle cx="{x10}" cy="{y}" r="5" fill="none" stroke="#e67e22" stroke-width="2"/>"##.into(),
                format!("closest approach: {:.2} m to obstacle {}", c.distance, c.obstacle),
            ));
        }
        rows
    }
}

/// The map's projection: metres (north, east) to pixels, East to the right and North up.
struct Canvas {
    n0: f64,
    n1: f64,
    e0: f64,
    e1: f64,
    scale: f64,
}

impl Canvas {
    fn new((n0, n1, e0, e1): (f64, f64, f64, f64)) -> Self {
        let scale = (SIZE_PX - 2.0 * MARGIN_PX) / (n1 - n0);
        Self { n0, n1, e0, e1, scale }
    }

    fn px(&self, n: f64, e: f64) -> (f64, f64) {
        (
            MARGIN_PX + (e - self.e0) * self.scale,
            MARGIN_PX + (self.n1 - n) * self.scale,
        )
    }

    /// SVG `points` of `pts`.
    fn poly(&self, pts: &[(f64, f64)]) -> String {
        pts.iter()
            .map(|&(n, e)| {
                let (x, y) = self.px(n, e);
                format!("{x:.1},{y:.1}")
            })
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// Grid lines every 10 m, labelled.
    fn grid(&self, s: &mut String) {
        let (n0, n1, e0, e1) = (self.n0, self.n1, self.e0, self.e1);
        let mut g = (n0 / 10.0).ceil() * 10.0;
        while g <= n1 {
            let (x0, y) = self.px(g, e0);
            let (x1, _) = self.px(g, e1);
            let _ = writeln!(
                s,
                r##"<line x1="{x0:.1}" y1="{y:.1}" x2="{x1:.1}" y2="{y:.1}" stroke="#eee"/><text x="4" y="{:.1}" fill="#999">N {g:.0}</text>"##,
                y + 4.0
            );
            g += 10.0;
        }
        let mut g = (e0 / 10.0).ceil() * 10.0;
        while g <= e1 {
            let (x, y0) = self.px(n1, g);
            let (_, y1) = self.px(n0, g);
            let _ = writeln!(
                s,
                r##"<line x1="{x:.1}" y1="{y0:.1}" x2="{x:.1}" y2="{y1:.1}" stroke="#eee"/><text x="{:.1}" y="{:.1}" fill="#999">E {g:.0}</text>"##,
                x - 10.0,
                y1 + 14.0
            );
            g += 10.0;
        }
    }
}

/// The competition's obstacle area, dashed.
fn obstacle_area(c: &Canvas, s: &mut String, a: &Arena) {
    let oda = [
        (a.x.min, a.y.min),
        (a.x.min, a.y.max),
        (a.x.max, a.y.max),
        (a.x.max, a.y.min),
    ];
    let _ = writeln!(
        s,
        r##"<polygon points="{}" fill="#fff8e0" stroke="#d9b24a" stroke-dasharray="6 4"/>"##,
        c.poly(&oda)
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Obstacle, Sample};
    use std::path::Path;

    #[test]
    fn svg_has_every_layer() {
        let test = TestCase::load(Path::new("missions/mission2.yaml"))
            .unwrap()
            .with_obstacles(vec![Obstacle::new(10.0, 5.0, 20.0, 10.0, 20.0, 0.0)]);
        let mut plot = FlightPlot::new(&test);
        let t = Trajectory::new(
            (0..10)
                .map(|i| Sample {
                    t_s: i as f64,
                    x: 0.0,
                    y: i as f64 * 5.0,
                    z: 10.0,
                    r: None,
                })
                .collect(),
        );
        plot.add_path(&t, PathStyle::Simulated, "simulated <paper>");
        plot.add_path(&t, PathStyle::Flown, "flown");
        plot.mark_closest(&ClosestApproach {
            t_s: 4.0,
            x: 0.0,
            y: 20.0,
            z: 10.0,
            obstacle: 0,
            distance: 5.0,
        });
        let svg = plot.to_svg();
        assert!(svg.starts_with("<svg") && svg.ends_with("</svg>\n"));
        assert_eq!(svg.matches("<polyline").count(), 3, "mission + 2 paths");
        assert!(svg.contains("simulated &lt;paper&gt;") && svg.contains("closest approach: 5.00 m"));
        assert!(svg.contains("obstacle area") && svg.contains("#c0392b"));
    }
}
