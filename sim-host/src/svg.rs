//! A picture of one run: obstacles, the reference path, the driven path,
//! start and goal, the collision points the planner saw, the remembered
//! points and their midpoint, and the virtual obstacles; and where the
//! planners' margin makes the way longer than the disc's, that way too.

use crate::geom::V2;
use crate::reference::Reference;
use crate::scenario::Scenario;
use crate::sim::RunResult;
use std::fmt::Write;

/// The map's longer side, and the least width of the picture (the title,
/// the figures line and the legend fit it), px.
const MAP_PX: f64 = 900.0;

/// How much longer than the reference the way with the planners' margin
/// must be to be drawn (in most worlds the two lie on one another).
const MARGIN_DRAWN_ABOVE: f64 = 1.01;

/// The SVG document for a run: `reference` is the disc's shortest way,
/// `with_margin` the shortest for the disc plus the planners' clearance
/// (drawn when longer than the reference by more than 1 %, and named in the
/// figures line when there is none).
pub fn render(
    sc: &Scenario,
    run: &RunResult,
    planner: &str,
    reference: Option<&Reference>,
    with_margin: Option<&Reference>,
) -> String {
    let (mut s, frame) = Frame::open(sc);
    let (scale, width) = (frame.scale, frame.width);
    let px = |p: V2| frame.px(p);
    // Title and figures.
    let colour = match run.outcome.as_str() {
        "reached" => "#1a7f37",
        "collision" => "#cf222e",
        "unreachable" => "#9a6700",
        _ => "#6e7781",
    };
    // A collision says what the disc touched, and whether it was driving.
    let contact = run
        .contact
        .map(|c| format!(" ({})", c.describe()))
        .unwrap_or_default();
    let _ = writeln!(
        s,
        r##"<text x="10" y="24" font-size="18" font-weight="bold">{} — {planner}: <tspan fill="{colour}">{}{contact}</tspan></text>"##,
        xml(&sc.name),
        run.outcome.as_str()
    );
    let mut ratio = reference
        .map(|r| {
            format!(
                ", {:.2}× the reference {:.2} m",
                run.path_length / r.length,
                r.length
            )
        })
        .unwrap_or_default();
    let margin_drawn = match (reference, with_margin) {
        (Some(r), Some(m)) => m.length > MARGIN_DRAWN_ABOVE * r.length,
        (None, Some(_)) => true,
        (_, None) => false,
    };
    match with_margin {
        Some(m) if margin_drawn => ratio += &format!(" ({:.2} m with the margin)", m.length),
        None if reference.is_some() => ratio += " (no way with the margin)",
        _ => {}
    }
    // A run known from telemetry alone has no clearance to tell.
    let clearance = if run.min_clearance.is_finite() {
        format!(", min clearance {:.3} m", run.min_clearance)
    } else {
        String::new()
    };
    let _ = writeln!(
        s,
        r##"<text x="10" y="48" font-size="13" fill="#444">{} steps, path {:.2} m{ratio}{clearance}, {} virtual obstacles</text>"##,
        run.steps, run.path_length, run.virtual_dropped
    );
    frame.obstacles(&mut s, sc);
    // Moving circles: their runs (thin dashes), where they began (a
    // dashed ring) and where they were when the run ended (grey), so that
    // a picture of a collision shows what reached the rover.
    let t_end = run.trace.last().map_or(0.0, |r| r.t);
    let movers = sc.world().moving;
    for (m, moving) in sc.moving.iter().zip(&movers) {
        let mut way = vec![V2::new(m.center[0], m.center[1])];
        way.extend(m.waypoints.iter().map(|w| V2::new(w[0], w[1])));
        let _ = writeln!(
            s,
            r##"<polyline points="{}" fill="none" stroke="#57606a" stroke-width="1" stroke-dasharray="2 3"/>"##,
            poly(&way, &px)
        );
        let (cx, cy) = px(way[0]);
        let r = m.radius * scale;
        let _ = writeln!(
            s,
            r##"<circle cx="{cx:.1}" cy="{cy:.1}" r="{r:.1}" fill="none" stroke="#57606a" stroke-dasharray="4 3"/>"##
        );
        let (ex, ey) = px(moving.center_at(t_end));
        let _ = writeln!(
            s,
            r##"<circle cx="{ex:.1}" cy="{ey:.1}" r="{r:.1}" fill="#8c959f" fill-opacity="0.6" stroke="#57606a"/>"##
        );
    }
    // Virtual obstacles.
    for (c, r) in &run.virtual_obstacles {
        let (cx, cy) = px(*c);
        let _ = writeln!(
            s,
            r##"<circle cx="{cx:.1}" cy="{cy:.1}" r="{:.1}" fill="#54aeff" fill-opacity="0.25" stroke="#0969da" stroke-dasharray="3 2"/>"##,
            r * scale
        );
    }
    // Reference path.
    if let Some(r) = reference {
        let _ = writeln!(
            s,
            r##"<polyline points="{}" fill="none" stroke="#2da44e" stroke-width="2" stroke-dasharray="6 4" opacity="0.8"/>"##,
            poly(&r.path, &px)
        );
    }
    // The way with the planners' margin, where it is not the reference's.
    if let Some(m) = with_margin.filter(|_| margin_drawn) {
        let _ = writeln!(
            s,
            r##"<polyline points="{}" fill="none" stroke="#1b7c83" stroke-width="2" stroke-dasharray="1 4" stroke-linecap="round"/>"##,
            poly(&m.path, &px)
        );
    }
    // The route over the known map (planner `route`), and its waypoints.
    if !run.route.is_empty() {
        let _ = writeln!(
            s,
            r##"<polyline points="{}" fill="none" stroke="#bf8700" stroke-width="1.5" stroke-dasharray="2 3"/>"##,
            poly(&run.route, &px)
        );
        for q in &run.route {
            let (a, b) = px(*q);
            let _ = writeln!(
                s,
                r##"<rect x="{:.1}" y="{:.1}" width="6" height="6" fill="#bf8700"/>"##,
                a - 3.0,
                b - 3.0
            );
        }
    }
    // Driven path, with the robot's width as a faint band.
    let path: Vec<V2> = run.trace.iter().map(|t| V2::new(t.x, t.y)).collect();
    let _ = writeln!(
        s,
        r##"<polyline points="{}" fill="none" stroke="#0969da" stroke-width="{:.1}" stroke-linejoin="round" opacity="0.12"/>"##,
        poly(&path, &px),
        2.0 * sc.robot_radius * scale
    );
    let _ = writeln!(
        s,
        r##"<polyline points="{}" fill="none" stroke="#0550ae" stroke-width="2" stroke-linejoin="round"/>"##,
        poly(&path, &px)
    );
    // What the planner saw and remembered.
    for q in &run.seen {
        let (a, b) = px(*q);
        let _ = writeln!(
            s,
            r##"<circle cx="{a:.1}" cy="{b:.1}" r="2.5" fill="#fb8500"/>"##
        );
    }
    for q in &run.remembered {
        let (a, b) = px(*q);
        let _ = writeln!(
            s,
            r##"<path d="M{:.1},{:.1} l8,8 m0,-8 l-8,8" stroke="#8250df" stroke-width="2"/>"##,
            a - 4.0,
            b - 4.0
        );
    }
    if let Some(m) = run.midpoint {
        let (a, b) = px(m);
        let _ = writeln!(
            s,
            r##"<circle cx="{a:.1}" cy="{b:.1}" r="9" fill="none" stroke="#8250df" stroke-width="2.5"/>"##
        );
    }
    // Start, goal, final pose.
    frame.start_and_goal(&mut s, sc);
    if let Some(last) = run.trace.last() {
        let (a, b) = px(V2::new(last.x, last.y));
        let (hx, hy) = (
            last.heading.cos() * sc.robot_radius * scale,
            -last.heading.sin() * sc.robot_radius * scale,
        );
        let _ = writeln!(
            s,
            r##"<circle cx="{a:.1}" cy="{b:.1}" r="{:.1}" fill="#0969da" fill-opacity="0.5" stroke="#0550ae"/><line x1="{a:.1}" y1="{b:.1}" x2="{:.1}" y2="{:.1}" stroke="#fff" stroke-width="2"/>"##,
            sc.robot_radius * scale,
            a + hx,
            b + hy
        );
    }
    // Legend.
    let items = [
        ("#0550ae", "driven path"),
        ("#2da44e", "reference"),
        ("#fb8500", "collision points seen"),
        ("#8250df", "remembered / midpoint"),
        ("#54aeff", "virtual obstacles"),
    ];
    let margin_item = [("#1b7c83", "with margin")];
    let route_item = [("#bf8700", "route")];
    let items: Vec<_> = items
        .iter()
        .chain(if margin_drawn {
            &margin_item[..]
        } else {
            &[][..]
        })
        .chain(if run.route.is_empty() {
            &[][..]
        } else {
            &route_item[..]
        })
        .collect();
    let mut lx = width - 10.0;
    for (c, label) in items.iter().rev() {
        lx -= 7.0 * label.len() as f64 + 22.0;
        let _ = writeln!(
            s,
            r##"<rect x="{lx:.1}" y="62" width="12" height="12" fill="{c}"/><text x="{:.1}" y="73" font-size="12">{label}</text>"##,
            lx + 16.0
        );
    }
    s.push_str("</svg>\n");
    s
}

/// Where a world goes in a picture: the map's scale and place under the
/// title lines and legend.
struct Frame {
    scale: f64,
    width: f64,
    ox: f64,
    x0: f64,
    y1: f64,
}

/// The height of the title lines and legend above the map, px.
const LEGEND_H: f64 = 86.0;

impl Frame {
    /// The document's opening for a picture of `sc`: its size, a white
    /// background and the map's frame.
    fn open(sc: &Scenario) -> (String, Frame) {
        let [x0, y0, x1, y1] = sc.bounds;
        let (w, h) = (x1 - x0, y1 - y0);
        let scale = MAP_PX / w.max(h);
        let (pw, ph) = (w * scale, h * scale);
        // A tall world (BARN's) is narrower than the title, the figures line
        // and the legend: the picture keeps their width, the map in its middle.
        let width = pw.max(MAP_PX);
        let ox = (width - pw) / 2.0;
        let legend_h = LEGEND_H;
        let mut s = String::new();
        let _ = writeln!(
            s,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0}" height="{:.0}" viewBox="0 0 {width:.1} {:.1}" font-family="sans-serif">"#,
            ph + legend_h,
            ph + legend_h
        );
        let _ = writeln!(
            s,
            r##"<rect x="0" y="0" width="{width:.1}" height="{:.1}" fill="#fff"/>"##,
            ph + legend_h
        );
        let _ = writeln!(
            s,
            r##"<rect x="{ox:.1}" y="{legend_h}" width="{pw:.1}" height="{ph:.1}" fill="#fbfaf7" stroke="#333" stroke-width="3"/>"##
        );
        (
            s,
            Frame {
                scale,
                width,
                ox,
                x0,
                y1,
            },
        )
    }

    /// World metres to picture pixels.
    fn px(&self, p: V2) -> (f64, f64) {
        (
            (p.x - self.x0) * self.scale + self.ox,
            (self.y1 - p.y) * self.scale + LEGEND_H,
        )
    }

    /// The still obstacles: circles and polygons.
    fn obstacles(&self, s: &mut String, sc: &Scenario) {
        let scale = self.scale;
        for c in &sc.circle {
            let (cx, cy) = self.px(V2::new(c.center[0], c.center[1]));
            let _ = writeln!(
                s,
                r##"<circle cx="{cx:.1}" cy="{cy:.1}" r="{:.1}" fill="#8c959f" stroke="#57606a"/>"##,
                c.radius * scale
            );
        }
        for p in &sc.polygon {
            let pts: Vec<String> = p
                .points
                .iter()
                .map(|q| {
                    let (a, b) = self.px(V2::new(q[0], q[1]));
                    format!("{a:.1},{b:.1}")
                })
                .collect();
            let _ = writeln!(
                s,
                r##"<polygon points="{}" fill="#8c959f" stroke="#57606a" stroke-width="0.5"/>"##,
                pts.join(" ")
            );
        }
    }

    /// Start (green disc) and goal (red ring).
    fn start_and_goal(&self, s: &mut String, sc: &Scenario) {
        let (sx, sy) = self.px(V2::new(sc.start[0], sc.start[1]));
        let (gx, gy) = self.px(V2::new(sc.goal[0], sc.goal[1]));
        let r = sc.robot_radius * self.scale;
        let _ = writeln!(
            s,
            r##"<circle cx="{sx:.1}" cy="{sy:.1}" r="{r:.1}" fill="#2da44e" stroke="#116329" stroke-width="2"/>"##,
        );
        let _ = writeln!(
            s,
            r##"<circle cx="{gx:.1}" cy="{gy:.1}" r="{r:.1}" fill="none" stroke="#cf222e" stroke-width="3"/><circle cx="{gx:.1}" cy="{gy:.1}" r="3" fill="#cf222e"/>"##,
        );
    }
}

/// One colour per planner in an overlay, in the order given.
const OVERLAY_COLOURS: [&str; 10] = [
    "#0550ae", "#cf222e", "#8250df", "#bf8700", "#1a7f37", "#e16f24", "#1b7c83", "#bf3989",
    "#57606a", "#0a3069",
];

/// One world with several planners' runs on it: each driven path in its
/// own colour, the reference path, start and goal, and a legend naming
/// each planner with its outcome.
pub fn overlay(
    sc: &Scenario,
    runs: &[(&str, &RunResult)],
    reference: Option<&Reference>,
) -> String {
    let (mut s, frame) = Frame::open(sc);
    let px = |p: V2| frame.px(p);
    let _ = writeln!(
        s,
        r##"<text x="10" y="24" font-size="18" font-weight="bold">{} — every planner</text>"##,
        xml(&sc.name)
    );
    if let Some(r) = reference {
        let _ = writeln!(
            s,
            r##"<text x="10" y="48" font-size="13" fill="#444">reference {:.2} m (green dashes)</text>"##,
            r.length
        );
    }
    frame.obstacles(&mut s, sc);
    for m in &sc.moving {
        let (cx, cy) = px(V2::new(m.center[0], m.center[1]));
        let _ = writeln!(
            s,
            r##"<circle cx="{cx:.1}" cy="{cy:.1}" r="{:.1}" fill="none" stroke="#57606a" stroke-dasharray="4 3"/>"##,
            m.radius * frame.scale
        );
    }
    if let Some(r) = reference {
        let _ = writeln!(
            s,
            r##"<polyline points="{}" fill="none" stroke="#2da44e" stroke-width="2" stroke-dasharray="6 4" opacity="0.8"/>"##,
            poly(&r.path, &px)
        );
    }
    for (i, (_, run)) in runs.iter().enumerate() {
        let path: Vec<V2> = run.trace.iter().map(|t| V2::new(t.x, t.y)).collect();
        let _ = writeln!(
            s,
            r##"<polyline points="{}" fill="none" stroke="{}" stroke-width="2" stroke-linejoin="round" opacity="0.85"/>"##,
            poly(&path, &px),
            OVERLAY_COLOURS[i % OVERLAY_COLOURS.len()]
        );
    }
    frame.start_and_goal(&mut s, sc);
    // The legend: two rows under the title.
    let per_row = runs.len().div_ceil(2).max(1);
    for (i, (name, run)) in runs.iter().enumerate() {
        let (row, col) = (i / per_row, i % per_row);
        let lx = 10.0 + col as f64 * (frame.width - 20.0) / per_row as f64;
        let ly = 56.0 + row as f64 * 16.0;
        let _ = writeln!(
            s,
            r##"<rect x="{lx:.1}" y="{ly:.1}" width="12" height="12" fill="{}"/><text x="{:.1}" y="{:.1}" font-size="12">{} ({})</text>"##,
            OVERLAY_COLOURS[i % OVERLAY_COLOURS.len()],
            lx + 16.0,
            ly + 11.0,
            xml(name),
            run.outcome.as_str()
        );
    }
    s.push_str("</svg>\n");
    s
}

fn poly(pts: &[V2], px: &dyn Fn(V2) -> (f64, f64)) -> String {
    pts.iter()
        .map(|&p| {
            let (a, b) = px(p);
            format!("{a:.1},{b:.1}")
        })
        .collect::<Vec<_>>()
        .join(" ")
}

fn xml(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}
