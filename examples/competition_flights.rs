//! Why the competition's simulator flew slowly and close to the boxes: speed profiles, stops, latched crawls,
//! clearance and time at altitude of the recorded tier-A flights (PX4 v1.12.3 + PX4-Avoidance + Gazebo), per
//! source (the repository that published them), beside PX4 v1.14 SIH with our companion on the same cases;
//! then the speeds PX4-Avoidance's FOV taper and PX4's braking law imply, and the bench's own timing.
//! The tables of docs/validation/competition-bench.md.
//!
//! `cargo run --release --example competition_flights -- [DIR=tests/data/hfs-flights]
//! [PX4_DIR=tests/data/px4-flights] [HELDOUT=tests/data/px4-heldout/px4]` (env `TRACE=ID`: also print that
//! case's speed and clearance per 10 s, recorded and on PX4; `PX4_LABEL=NAME`: what the PX4_DIR flights are
//! called in the tables, for example `PX4_LABEL="competition bench"` with `tests/data/competition-bench-fit/h90c23`)

#[path = "common/flight_stats.rs"]
mod flight_stats;
#[path = "common/flight_summary.rs"]
mod flight_summary;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use flight_stats::{CRAWL_BAND, CRAWL_MIN_S, Cruise, STOP_BELOW, STOP_MIN_S, Track, median, px4_track, recorded_track};
use flight_summary::{Crawl, Flight, Stop, analyse, braking_speed, f2, lock_replay_s, range, trace};
use prgenuav::lfs::fidelity::{load_dir, spearman};
use prgenuav::lfs::px4_flights;

/// One row of the per-source table.
fn source_row(name: &str, fl: &[&Flight]) {
    if fl.is_empty() {
        return;
    }
    let per = |f: &dyn Fn(&Flight) -> f64| fl.iter().map(|x| f(x)).collect::<Vec<f64>>();
    let time: f64 = fl.iter().map(|f| f.t_alt()).sum();
    let pooled = |keep: &dyn Fn(&Cruise, usize) -> bool| {
        fl.iter().map(|f| f.c.time_where(|i| keep(&f.c, i))).sum::<f64>() / time.max(1e-9)
    };
    let stops: usize = fl.iter().map(|f| f.stops.len()).sum();
    let turned = fl
        .iter()
        .flat_map(|f| &f.stops)
        .filter(|s| s.course_deg.is_some_and(|c| c > 30.0))
        .count();
    let crawl: f64 = fl.iter().map(|f| f.crawl_s()).sum();
    println!(
        "| {name} | {} | {} | {} | {} | {:.0} % | {:.0} % ({} flights) | {:.2} | {turned} of {stops} | {:.0} % |",
        fl.len(),
        range(&per(&|f| f.t_alt()), 0),
        range(&per(&|f| f.v_med()), 2),
        range(&per(&|f| f.v_p90()), 2),
        100.0 * pooled(&|c, i| c.v[i] < 0.2) + 0.0,
        100.0 * crawl / time.max(1e-9) + 0.0,
        fl.iter().filter(|f| !f.crawls.is_empty()).count(),
        stops as f64 / (time / 60.0).max(1e-9),
        100.0 * pooled(&|c, i| c.turning[i]),
    );
}

const CLEAR_BINS: [(f64, f64); 5] = [(0.0, 1.5), (1.5, 3.0), (3.0, 5.0), (5.0, 8.0), (8.0, f64::INFINITY)];

/// Share of cruise time and median speed per clearance bin.
fn clearance_row(name: &str, fl: &[&Flight], keep: &dyn Fn(&Flight, usize) -> bool) {
    let total: f64 = fl.iter().map(|f| f.c.time_where(|i| keep(f, i))).sum();
    let cells: Vec<String> = CLEAR_BINS
        .iter()
        .map(|&(lo, hi)| {
            let inside = |f: &Flight, i: usize| keep(f, i) && f.c.clear[i] >= lo && f.c.clear[i] < hi;
            let share = fl.iter().map(|f| f.c.time_where(|i| inside(f, i))).sum::<f64>() / total.max(1e-9);
            let v: Vec<f64> = fl
                .iter()
                .flat_map(|f| (0..f.c.t.len()).filter(|&i| inside(f, i)).map(|i| f.c.v[i]))
                .collect();
            format!("{:.0} % / {}", 100.0 * share + 0.0, f2(median(&v)))
        })
        .collect();
    println!("| {name} | {} |", cells.join(" | "));
}

/// What the second folder's flights are called (env `PX4_LABEL`, read once; the default is the folder's usual
/// content).
fn label() -> &'static str {
    static LABEL: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    LABEL.get_or_init(|| std::env::var("PX4_LABEL").unwrap_or_else(|_| "PX4 v1.14 SIH".into()))
}

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let dir = PathBuf::from(args.next().unwrap_or_else(|| "tests/data/hfs-flights".into()));
    let px4_dir = PathBuf::from(args.next().unwrap_or_else(|| "tests/data/px4-flights".into()));
    let heldout = PathBuf::from(args.next().unwrap_or_else(|| "tests/data/px4-heldout/px4".into()));
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    files.sort();
    let rec_tracks: Vec<Track> = files.iter().filter_map(|p| recorded_track(p)).collect();
    let (cases, _) = load_dir(&dir)?;
    let px4: BTreeMap<String, px4_flights::Px4Flight> = px4_flights::load(&px4_dir, &cases)?
        .into_iter()
        .map(|f| (f.id.clone(), f))
        .collect();
    let px4_tracks: Vec<Track> = rec_tracks
        .iter()
        .filter_map(|t| {
            let f = px4.get(&t.id).filter(|f| f.status == "landed")?;
            px4_track(&px4_dir, t, f.min_distance)
        })
        .collect();
    let rec: Vec<Flight> = rec_tracks.iter().filter_map(analyse).collect();
    let sih: Vec<Flight> = px4_tracks.iter().filter_map(analyse).collect();
    let sih_by_id: BTreeMap<&str, &Flight> = sih.iter().map(|f| (f.id.as_str(), f)).collect();
    println!(
        "{} recorded tier-A flights ({} with boxes, {} landed), {} of their cases flown on {px4} and landed",
        rec.len(),
        rec.iter().filter(|f| f.d.is_some()).count(),
        rec_tracks.iter().filter(|t| t.landed == Some(true)).count(),
        sih.len(),
        px4 = label()
    );
    if let Ok(id) = std::env::var("TRACE") {
        for f in rec.iter().chain(&sih).filter(|f| f.id == id) {
            trace(f);
        }
    }

    println!("\n## 1. Cruise (above 8 m) per source\n");
    println!(
        "Speeds over {}-s windows. Latched crawl: at least {CRAWL_MIN_S} s in {}-{} m/s. Stops: below {STOP_BELOW} m/s for {STOP_MIN_S} s or more (turned: course before and after differs by > 30 degrees). Turning: PX4 v1.12.3's lock condition holds (speed > 0.2 m/s and the velocity more than 11.5 degrees off its internal target, the closest point of the leg when more than NAV_ACC_RAD off it).\n",
        flight_stats::SPEED_WINDOW_S,
        CRAWL_BAND.0,
        CRAWL_BAND.1
    );
    println!(
        "| flights | n | time at altitude s | median speed m/s (flights' medians) | p90 speed m/s | time below 0.2 m/s | time in latched crawl | stops per minute | stops that turned | time turning (v1.12.3 lock armed) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let mut sources: Vec<&str> = rec.iter().map(|f| f.source.as_str()).collect();
    sources.sort_unstable();
    sources.dedup();
    for s in &sources {
        source_row(
            &format!("recorded, {s}"),
            &rec.iter().filter(|f| f.source == *s).collect::<Vec<_>>(),
        );
    }
    for s in &sources {
        let mine = |f: &&Flight| f.source == *s;
        if rec.iter().filter(mine).any(|f| !f.crawls.is_empty()) {
            let fast: Vec<&Flight> = rec.iter().filter(mine).filter(|f| f.crawls.is_empty()).collect();
            source_row(&format!("recorded, {s}, without a latched crawl"), &fast);
        }
    }
    source_row("recorded, all", &rec.iter().collect::<Vec<_>>());
    source_row(
        "recorded, with a latched crawl",
        &rec.iter().filter(|f| !f.crawls.is_empty()).collect::<Vec<_>>(),
    );
    source_row(
        "recorded, without",
        &rec.iter().filter(|f| f.crawls.is_empty()).collect::<Vec<_>>(),
    );
    source_row(&format!("{}, same cases", label()), &sih.iter().collect::<Vec<_>>());
    for s in &sources {
        let ids: Vec<&str> = rec.iter().filter(|f| f.source == *s).map(|f| f.id.as_str()).collect();
        source_row(
            &format!("{}, {s}'s cases", label()),
            &sih.iter().filter(|f| ids.contains(&f.id.as_str())).collect::<Vec<_>>(),
        );
    }

    println!("\n## 2. Per flight: recorded / {}\n", label());
    println!(
        "| case | source | s per px | time at altitude s | median m/s | p90 m/s | latched crawl s | stops | distance m |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for f in &rec {
        let p = sih_by_id.get(f.id.as_str());
        let pair = |a: String, b: Option<String>| format!("{a} / {}", b.unwrap_or_else(|| "-".into()));
        println!(
            "| {} | {} | {} | {} | {} | {} | {:.0} | {} | {} |",
            f.id,
            f.source,
            f.t_px.map_or("-".into(), f2),
            pair(format!("{:.0}", f.t_alt()), p.map(|p| format!("{:.0}", p.t_alt()))),
            pair(f2(f.v_med()), p.map(|p| f2(p.v_med()))),
            pair(f2(f.v_p90()), p.map(|p| f2(p.v_p90()))),
            f.crawl_s() + 0.0,
            pair(f.stops.len().to_string(), p.map(|p| p.stops.len().to_string())),
            pair(f.d.map_or("-".into(), f2), p.and_then(|p| p.d).map(f2)),
        );
    }

    crawl_tables(&rec, &sih);
    clearance_tables(&rec, &sih);
    stop_tables(&rec, &sih);
    distance_tables(&rec, &sih_by_id);
    time_table(&rec, &sih_by_id);
    formula_table();
    bench_timing(&px4, &heldout);
    Ok(())
}

fn crawl_tables(rec: &[Flight], sih: &[Flight]) {
    println!("\n## 3. Latched crawls\n");
    println!(
        "| case | start s | duration s | median m/s | lowest 1-s speed in the 10 s before, m/s | share off the line | share turning | ended | highest m/s in the 15 s after |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let all: Vec<(&Flight, &Crawl)> = rec.iter().flat_map(|f| f.crawls.iter().map(move |c| (f, c))).collect();
    for (f, c) in &all {
        println!(
            "| {} | {:.0} | {:.0} | {:.2} | {:.2} | {:.2} | {:.2} | {} | {:.2} |",
            f.id, c.start_s, c.dur_s, c.v_med, c.pre_min, c.off_share, c.turning_share, c.end, c.after_max
        );
    }
    let v: Vec<f64> = all.iter().map(|(_, c)| c.v_med).collect();
    let off: Vec<f64> = all.iter().map(|(_, c)| c.off_share).collect();
    let turning: Vec<f64> = all.iter().map(|(_, c)| c.turning_share).collect();
    let mut ends: BTreeMap<&str, usize> = BTreeMap::new();
    for (_, c) in &all {
        *ends.entry(c.end).or_default() += 1;
    }
    let armed_low = all.iter().filter(|(_, c)| c.pre_min < 0.2).count();
    println!(
        "\n{} latched crawls in {} of {} recorded flights; median speed {} m/s; share off the line {}; share turning {}; preceded by a 1-s speed below 0.2 m/s: {armed_low}; ended: {ends:?}",
        all.len(),
        rec.iter().filter(|f| !f.crawls.is_empty()).count(),
        rec.len(),
        range(&v, 2),
        range(&off, 2),
        range(&turning, 2)
    );
    println!(
        "{}: {} latched crawls in {} flights",
        label(),
        sih.iter().map(|f| f.crawls.len()).sum::<usize>(),
        sih.len()
    );
}

fn boxed(v: &[Flight]) -> Vec<&Flight> {
    v.iter().filter(|f| f.d.is_some()).collect()
}

fn clearance_tables(rec: &[Flight], sih: &[Flight]) {
    println!("\n## 4. Speed by clearance (distance to the nearest box): share of cruise time / median speed m/s\n");
    let head: Vec<String> = CLEAR_BINS
        .iter()
        .map(|(a, b)| {
            if b.is_finite() {
                format!("{a}-{b} m")
            } else {
                format!("{a} m and more")
            }
        })
        .collect();
    println!("| flights | {} |\n|---|{}", head.join(" | "), "---|".repeat(head.len()));
    let in_crawl = |f: &Flight, i: usize| {
        let t = f.c.t[i] - f.c.t[0];
        f.crawls.iter().any(|c| t >= c.start_s && t <= c.start_s + c.dur_s)
    };
    clearance_row("recorded", &boxed(rec), &|_, _| true);
    clearance_row("recorded, outside latched crawls", &boxed(rec), &|f, i| !in_crawl(f, i));
    clearance_row("recorded, inside latched crawls", &boxed(rec), &in_crawl);
    clearance_row(label(), &boxed(sih), &|_, _| true);
}

fn stop_tables(rec: &[Flight], sih: &[Flight]) {
    println!("\n## 5. Stops (hover): duration, clearance, turn\n");
    println!(
        "| flights | stops | per flight | duration s | clearance at the stop m | course change > 30 deg | heading change > 30 deg |"
    );
    println!("|---|---|---|---|---|---|---|");
    for (name, fl) in [("recorded", rec), (label(), sih)] {
        let s: Vec<&Stop> = fl.iter().flat_map(|f| &f.stops).collect();
        let dur: Vec<f64> = s.iter().map(|x| x.dur_s).collect();
        let clear: Vec<f64> = s.iter().map(|x| x.clear_m).filter(|c| c.is_finite()).collect();
        let share = |pick: &dyn Fn(&Stop) -> Option<f64>| {
            let known: Vec<f64> = s.iter().filter_map(|x| pick(x)).collect();
            format!("{} of {}", known.iter().filter(|&&c| c > 30.0).count(), known.len())
        };
        println!(
            "| {name} | {} | {:.1} | {} | {} | {} | {} |",
            s.len(),
            s.len() as f64 / fl.len().max(1) as f64,
            range(&dur, 1),
            range(&clear, 1),
            share(&|x| x.course_deg),
            share(&|x| x.heading_deg)
        );
    }
}

fn distance_tables(rec: &[Flight], sih: &BTreeMap<&str, &Flight>) {
    println!("\n## 6. Closest approach and speed\n");
    println!(
        "| flights | n | Spearman(speed within 5 s of the closest sample, distance) | Spearman(median cruise speed, distance) |"
    );
    println!("|---|---|---|---|");
    for (name, fl) in [
        ("recorded", rec.iter().collect::<Vec<_>>()),
        (label(), sih.values().copied().collect()),
    ] {
        let pairs: Vec<(f64, f64, f64)> = fl
            .iter()
            .filter_map(|f| Some((f.v_at_closest()?, f.v_med(), f.d?)))
            .collect();
        let (a, b, d): (Vec<f64>, Vec<f64>, Vec<f64>) = pairs.iter().fold((vec![], vec![], vec![]), |mut acc, p| {
            acc.0.push(p.0);
            acc.1.push(p.1);
            acc.2.push(p.2);
            acc
        });
        let s = |x: &[f64]| spearman(x, &d).map_or("-".into(), f2);
        println!("| {name} | {} | {} | {} |", pairs.len(), s(&a), s(&b));
    }
    println!(
        "\n| recorded flights | n | recorded distance m | PX4 distance m | PX4 - recorded m (mean, sd of the mean) |"
    );
    println!("|---|---|---|---|---|");
    for (name, crawled) in [("with a latched crawl", true), ("without", false)] {
        let g: Vec<(f64, f64)> = rec
            .iter()
            .filter(|f| f.crawls.is_empty() != crawled)
            .filter_map(|f| Some((f.d?, sih.get(f.id.as_str())?.d?)))
            .collect();
        let gap: Vec<f64> = g.iter().map(|(r, p)| p - r).collect();
        let n = gap.len().max(1) as f64;
        let mean = gap.iter().sum::<f64>() / n;
        let sd = (gap.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt() / n.sqrt();
        let r: Vec<f64> = g.iter().map(|x| x.0).collect();
        let p: Vec<f64> = g.iter().map(|x| x.1).collect();
        println!(
            "| {name} | {} | {} | {} | {mean:+.2} ({sd:.2}) |",
            g.len(),
            range(&r, 2),
            range(&p, 2)
        );
    }
}

fn time_table(rec: &[Flight], sih: &BTreeMap<&str, &Flight>) {
    println!("\n## 7. Time at altitude: recorded, recorded without its latched crawls, PX4\n");
    println!(
        "Without the crawls: each crawl's path flown at the flight's median speed outside crawls and stops. PX4 with the lock: PX4's flight with v1.12.3's turning lock replayed on its path (see `lock_replay_s`).\n"
    );
    println!(
        "| flights | n | recorded s | without crawls s | {} s | PX4 / recorded | PX4 / without crawls | PX4 with the lock replayed s | its flights slowed 2x or more |",
        label()
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for (name, crawled) in [
        ("with a latched crawl", Some(true)),
        ("without", Some(false)),
        ("all", None),
    ] {
        let rows: Vec<(f64, f64, f64, f64)> = rec
            .iter()
            .filter(|f| crawled.is_none_or(|c| f.crawls.is_empty() != c))
            .filter_map(|f| {
                let p = sih.get(f.id.as_str())?;
                let moving: Vec<f64> = (0..f.c.t.len())
                    .filter(|&i| f.c.v[i] >= CRAWL_BAND.1)
                    .map(|i| f.c.v[i])
                    .collect();
                let v_free = if moving.is_empty() { 1.3 } else { median(&moving) };
                let cf = f.t_alt() - f.crawl_s() + f.crawls.iter().map(|c| c.path_m).sum::<f64>() / v_free;
                Some((f.t_alt(), cf, p.t_alt(), lock_replay_s(&p.c)))
            })
            .collect();
        let col = |k: usize| rows.iter().map(|r| [r.0, r.1, r.2, r.3][k]).collect::<Vec<f64>>();
        let ratio = |k: usize| median(&rows.iter().map(|r| r.2 / [r.0, r.1][k]).collect::<Vec<f64>>());
        println!(
            "| {name} | {} | {} | {} | {} | {:.2} | {:.2} | {} | {} |",
            rows.len(),
            range(&col(0), 0),
            range(&col(1), 0),
            range(&col(2), 0),
            ratio(0),
            ratio(1),
            range(&col(3), 0),
            rows.iter().filter(|r| r.3 >= 2.0 * r.2).count()
        );
    }
}

fn formula_table() {
    println!("\n## 8. What the code implies (no data): PX4-Avoidance's FOV taper and PX4's braking law\n");
    println!(
        "The waypoint generator puts the setpoint `speed` metres ahead, speed = MPC_XY_CRUISE x (1 - 2|da|/h_fov) (0 outside the FOV; low-passed, tau 0.9 s); PX4 (v1.12.3 and v1.14 alike) flies towards an injected setpoint no faster than it can stop on it (MPC_JERK_AUTO 4, MPC_ACC_HOR 3).\n"
    );
    println!(
        "| goto off the camera axis, deg | FOV scale (h_fov 59 deg) | lead m (cruise 5) | PX4 speed m/s | lead m (cruise 2, the planner's fallback) | PX4 speed m/s |"
    );
    println!("|---|---|---|---|---|---|");
    for da in [0.0, 5.0, 10.0, 15.0, 20.0, 25.0, 29.5] {
        let scale = (1.0 - 2.0 * da / 59.0_f64).max(0.0);
        let v = |c: f64| braking_speed(4.0, 3.0, c * scale);
        println!(
            "| {da} | {scale:.2} | {:.2} | {:.2} | {:.2} | {:.2} |",
            5.0 * scale,
            v(5.0),
            2.0 * scale,
            v(2.0)
        );
    }
    // Inverse of the braking law at MPC_JERK_AUTO 4, MPC_ACC_HOR 3: v^2 + (4 a^2 / j) v = 2 a d.
    let lead_for = |v: f64| (v * v + 9.0 * v) / 6.0;
    println!(
        "\nLead that gives 1.32 m/s (the organisers' obstacle-free plateau): {:.2} m. PX4-Avoidance's sensor-range speed limit (MPC_ACC_HOR 3, MPC_JERK_MAX 8, 15 m): {:.2} m/s. Lead at the turning lock's 0.2 m/s: {:.2} m.",
        lead_for(1.32),
        {
            let (a, j, r) = (3.0_f64, 8.0_f64, 15.0_f64);
            let b = 2.0 * a * a / j;
            (-b + (b * b + 8.0 * a * r).sqrt()) / 2.0
        },
        lead_for(0.2)
    );
}

fn bench_timing(px4: &BTreeMap<String, px4_flights::Px4Flight>, heldout: &Path) {
    println!("\n## 9. The bench's companion ({})\n", label());
    let p99: Vec<f64> = px4.values().filter_map(|f| f.answer_p99_ms).collect();
    let not_landed = px4.values().filter(|f| f.status != "landed").count();
    println!(
        "Recorded cases: {} flights, {not_landed} not landed; answer latency p99 {} ms wall",
        px4.len(),
        range(&p99, 1)
    );
    let mut status: BTreeMap<String, usize> = BTreeMap::new();
    let mut lat = Vec::new();
    for e in std::fs::read_dir(heldout).into_iter().flatten().flatten() {
        let Ok(text) = std::fs::read_to_string(e.path()) else {
            continue;
        };
        let Ok(v) = serde_json::from_str::<serde_json::Value>(&text) else {
            continue;
        };
        *status
            .entry(v["status"].as_str().unwrap_or("?").to_string())
            .or_default() += 1;
        lat.extend(v["companion_timing"]["request_to_answer_ms"]["p99"].as_f64());
    }
    println!(
        "Held-out tests (HELDOUT): {status:?}; request-to-answer p99 {} ms wall",
        range(&lat, 1)
    );
}
