//! The picture of a run: a hand-written SVG of the occupancy grid, the trajectories and the
//! corners, with a title, a legend and a scale bar.
//!
//! The world (metres, y up) is mapped onto a canvas of at most [`MAX_MAP_W`] x
//! [`MAX_MAP_H`] pixels with y flipped, so every stroke width is a fixed number of pixels
//! and therefore a fixed fraction of the world's extent whatever its size.

use std::fmt::Write;

use back_end::occupancy_grid::GridCell;
use slam_geom::MapCorner;
use slam_geom::Se2Alignment;

const MAX_MAP_W: f64 = 1400.0;
const MAX_MAP_H: f64 = 1000.0;
/// Wide enough for the title and the legend even when the world is a narrow corridor.
const MIN_CANVAS_W: f64 = 1000.0;
const MARGIN: f64 = 24.0;
const FOOTER_H: f64 = 78.0;
/// A drawn cell smaller than this (pixels) renders as a faint smudge, so cells are merged
/// into coarser ones until they reach it; this also bounds the size of the file.
const MIN_CELL_PX: f64 = 1.5;
const FONT: &str = "DejaVu Sans, Helvetica, Arial, sans-serif";

const ESTIMATE: &str = "#1f66c2";
const TRUTH: &str = "#34a853";
const DEAD_RECKONING: &str = "#f08c00";
const MAP_CORNER: &str = "#d62728";
const TRUE_CORNER: &str = "#6a3d9a";
/// The grid's cells as map.png shows them (free white, unknown grey, occupied dark), the
/// grey paler so the trajectories stand out on it.
const FREE_CELL: &str = "#ffffff";
const UNKNOWN_CELL: &str = "#e2e2e2";
/// The grid's occupied cells: the walls.
const OCCUPIED_CELL: &str = "#555555";

/// Everything the picture shows, in one frame (metres). Empty slices are simply not drawn
/// (and left out of the legend).
#[derive(Debug, Clone, Copy)]
pub struct SvgInput<'a> {
    pub title: &'a str,
    /// Lines under the title, typically the key metrics.
    pub subtitle: &'a [String],
    /// A small line at the bottom, e.g. which frame the picture is in.
    pub note: &'a str,
    /// Edge of the cells of `cells`.
    pub cell_m: f64,
    /// The occupancy grid's free and occupied cells; the rest of their bounding box is drawn
    /// as unknown.
    pub cells: &'a [GridCell],
    /// Where the cells' grid sits in the picture's frame: the cells are accumulated in one
    /// frame (the SLAM frame) but may be drawn in another (the world's), rotated exactly by
    /// the SVG transform rather than re-binned, which would alias.
    pub cells_placement: Se2Alignment,
    pub trajectory: &'a [[f64; 2]],
    pub ground_truth: &'a [[f64; 2]],
    pub dead_reckoning: &'a [[f64; 2]],
    pub map_corners: &'a [MapCorner],
    pub true_corners: &'a [[f64; 2]],
}

/// The world-to-canvas mapping.
struct SvgView {
    /// Pixels per metre.
    k: f64,
    x0: f64,
    y0: f64,
    min: [f64; 2],
    max: [f64; 2],
    map_w: f64,
    map_h: f64,
    canvas_w: f64,
    /// Stroke unit in pixels.
    u: f64,
}

impl SvgView {
    fn px(&self, p: [f64; 2]) -> [f64; 2] {
        [
            self.x0 + (p[0] - self.min[0]) * self.k,
            self.y0 + (self.max[1] - p[1]) * self.k,
        ]
    }
}

/// Renders the picture. Deterministic: the same input gives the same bytes.
pub fn render_svg(input: &SvgInput<'_>) -> String {
    let header_h = 50.0 + 19.0 * input.subtitle.len() as f64;
    let view = view(input, header_h);
    let canvas_h = header_h + view.map_h + FOOTER_H;
    let mut svg = String::with_capacity(64 * 1024);
    // Writing to a String cannot fail, hence the ignored results below.
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w:.0}" height="{h:.0}" viewBox="0 0 {w:.0} {h:.0}" font-family="{FONT}">"#,
        w = view.canvas_w,
        h = canvas_h
    );
    let _ = writeln!(svg, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        svg,
        r##"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="none" stroke="#e2e2e2" stroke-width="1"/>"##,
        view.x0, view.y0, view.map_w, view.map_h
    );
    draw_cells(&mut svg, &view, input);
    let true_corner_paint = format!(
        r#"fill="none" stroke="{TRUE_CORNER}" stroke-width="{:.2}""#,
        1.5 * view.u
    );
    for p in input.true_corners {
        circle(&mut svg, view.px(*p), 7.0 * view.u, &true_corner_paint);
    }
    // The truth underlays the estimate as a wide pale band, so a good estimate runs inside it.
    let truth_style = format!(
        r#"stroke="{TRUTH}" stroke-opacity="0.55" stroke-width="{:.2}""#,
        5.0 * view.u
    );
    polyline(&mut svg, &view, input.ground_truth, &truth_style);
    let dr_style = format!(
        r#"stroke="{DEAD_RECKONING}" stroke-width="{:.2}" stroke-dasharray="{:.1} {:.1}""#,
        1.4 * view.u,
        7.0 * view.u,
        4.0 * view.u
    );
    polyline(&mut svg, &view, input.dead_reckoning, &dr_style);
    let estimate_style = format!(r#"stroke="{ESTIMATE}" stroke-width="{:.2}""#, 1.8 * view.u);
    polyline(&mut svg, &view, input.trajectory, &estimate_style);
    draw_endpoints(&mut svg, &view, input.trajectory);
    for corner in input.map_corners {
        map_corner_glyph(
            &mut svg,
            view.u,
            view.px([corner.x, corner.y]),
            corner.heading,
        );
    }
    draw_header(&mut svg, input);
    draw_footer(&mut svg, &view, input, header_h + view.map_h);
    svg.push_str("</svg>\n");
    svg
}

fn view(input: &SvgInput<'_>, header_h: f64) -> SvgView {
    let mut min = [f64::INFINITY; 2];
    let mut max = [f64::NEG_INFINITY; 2];
    let mut include = |p: [f64; 2]| {
        if p[0].is_finite() && p[1].is_finite() {
            for a in 0..2 {
                min[a] = min[a].min(p[a]);
                max[a] = max[a].max(p[a]);
            }
        }
    };
    // Half a rotated cell's extent, whatever the rotation.
    let half = input.cell_m * std::f64::consts::FRAC_1_SQRT_2;
    for c in input.cells {
        let centre = input.cells_placement.apply([
            (c.index[0] as f64 + 0.5) * input.cell_m,
            (c.index[1] as f64 + 0.5) * input.cell_m,
        ]);
        include([centre[0] - half, centre[1] - half]);
        include([centre[0] + half, centre[1] + half]);
    }
    let points = [
        input.trajectory,
        input.ground_truth,
        input.dead_reckoning,
        input.true_corners,
    ];
    points
        .iter()
        .flat_map(|s| s.iter())
        .for_each(|p| include(*p));
    input.map_corners.iter().for_each(|c| include([c.x, c.y]));
    if min[0] > max[0] {
        (min, max) = ([-1.0, -1.0], [1.0, 1.0]);
    }
    // A straight-line run would otherwise be a sliver of zero height.
    let longest = (max[0] - min[0]).max(max[1] - min[1]).max(1.0);
    let pad = 0.03 * longest;
    for a in 0..2 {
        let short = (0.1 * longest - (max[a] - min[a])).max(0.0) / 2.0;
        min[a] -= pad + short;
        max[a] += pad + short;
    }
    let (dx, dy) = (max[0] - min[0], max[1] - min[1]);
    let k = (MAX_MAP_W / dx).min(MAX_MAP_H / dy);
    let (map_w, map_h) = (dx * k, dy * k);
    let canvas_w = (map_w + 2.0 * MARGIN).max(MIN_CANVAS_W);
    SvgView {
        k,
        x0: (canvas_w - map_w) / 2.0,
        y0: header_h,
        min,
        max,
        map_w,
        map_h,
        canvas_w,
        u: map_w.max(map_h) / 1200.0,
    }
}

/// Draws the grid cells as one path per state, with runs of neighbouring cells in a row
/// merged into one rectangle: the file stays small even for a long run. Cells too small to
/// see are merged into coarser ones, occupied if any of them is: a wall stays visible.
fn draw_cells(svg: &mut String, view: &SvgView, input: &SvgInput<'_>) {
    if input.cells.is_empty() || !input.cell_m.is_finite() || input.cell_m <= 0.0 {
        return;
    }
    let factor = (MIN_CELL_PX / (input.cell_m * view.k)).ceil().max(1.0) as i64;
    let cell = input.cell_m * factor as f64;
    let merged = merge_cells(input.cells, factor);
    // Cell units map to pixels through one transform (placement, scale, y flip), so the
    // path holds small integers.
    let (sin, cos) = input.cells_placement.rotation.sin_cos();
    let [tx, ty] = input.cells_placement.translation;
    let scale = cell * view.k;
    let transform = format!(
        "matrix({a:.6} {b:.6} {c:.6} {d:.6} {e:.3} {f:.3})",
        a = scale * cos,
        b = -scale * sin,
        c = -scale * sin,
        d = -scale * cos,
        e = view.x0 + (tx - view.min[0]) * view.k,
        f = view.y0 + (view.max[1] - ty) * view.k
    );
    let (mut lo, mut hi) = ([i64::MAX; 2], [i64::MIN; 2]);
    for c in &merged {
        for a in 0..2 {
            lo[a] = lo[a].min(c.index[a]);
            hi[a] = hi[a].max(c.index[a] + 1);
        }
    }
    let _ = writeln!(
        svg,
        r#"<rect transform="{transform}" x="{}" y="{}" width="{}" height="{}" fill="{UNKNOWN_CELL}"/>"#,
        lo[0],
        lo[1],
        hi[0] - lo[0],
        hi[1] - lo[1]
    );
    for (occupied, colour) in [(false, FREE_CELL), (true, OCCUPIED_CELL)] {
        let d = run_path(merged.iter().filter(|c| c.occupied == occupied));
        if !d.is_empty() {
            let _ = writeln!(
                svg,
                r#"<path transform="{transform}" fill="{colour}" d="{d}"/>"#
            );
        }
    }
}

/// `cells` merged `factor` by `factor` into coarser ones, occupied if any of theirs is,
/// row by row from the lowest: a dense pass over their box, no sort.
fn merge_cells(cells: &[GridCell], factor: i64) -> Vec<GridCell> {
    let coarse = |c: &GridCell| [c.index[0].div_euclid(factor), c.index[1].div_euclid(factor)];
    let (mut lo, mut hi) = ([i64::MAX; 2], [i64::MIN; 2]);
    for c in cells {
        let index = coarse(c);
        for a in 0..2 {
            lo[a] = lo[a].min(index[a]);
            hi[a] = hi[a].max(index[a]);
        }
    }
    if cells.is_empty() {
        return Vec::new();
    }
    let width = (hi[0] - lo[0] + 1) as usize;
    let height = (hi[1] - lo[1] + 1) as usize;
    // 0 unknown, 1 free, 2 occupied: the larger wins.
    let mut states = vec![0_u8; width * height];
    for c in cells {
        let [x, y] = coarse(c);
        let state = &mut states[(y - lo[1]) as usize * width + (x - lo[0]) as usize];
        *state = (*state).max(1 + u8::from(c.occupied));
    }
    states
        .iter()
        .enumerate()
        .filter(|(_, state)| **state > 0)
        .map(|(i, state)| GridCell {
            index: [lo[0] + (i % width) as i64, lo[1] + (i / width) as i64],
            occupied: *state == 2,
        })
        .collect()
}

/// A path of unit squares, cells ordered by row then column; horizontal runs become one
/// rectangle and each subpath starts relative to the previous one to keep numbers short.
fn run_path<'a>(cells: impl Iterator<Item = &'a GridCell>) -> String {
    let mut d = String::new();
    let mut start: Option<[i64; 2]> = None;
    let mut run = 0_i64;
    let mut previous: Option<[i64; 2]> = None;
    let flush = |d: &mut String, start: [i64; 2], run: i64, previous: &mut Option<[i64; 2]>| {
        match previous {
            None => {
                let _ = write!(d, "M{} {}", start[0], start[1]);
            }
            Some(p) => {
                let _ = write!(d, "m{} {}", start[0] - p[0], start[1] - p[1]);
            }
        }
        let _ = write!(d, "h{run}v1h-{run}z");
        *previous = Some(start);
    };
    for c in cells {
        match start {
            Some(s) if s[1] == c.index[1] && s[0] + run == c.index[0] => run += 1,
            _ => {
                if let Some(s) = start {
                    flush(&mut d, s, run, &mut previous);
                }
                start = Some(c.index);
                run = 1;
            }
        }
    }
    if let Some(s) = start {
        flush(&mut d, s, run, &mut previous);
    }
    d
}

/// A polyline, leaving out points within half a pixel of the last one drawn.
fn polyline(svg: &mut String, view: &SvgView, points: &[[f64; 2]], style: &str) {
    if points.len() < 2 {
        return;
    }
    let mut coords = String::with_capacity(points.len() * 12);
    let mut last: Option<[f64; 2]> = None;
    for (i, p) in points.iter().enumerate() {
        let q = view.px(*p);
        if !(q[0].is_finite() && q[1].is_finite()) {
            continue;
        }
        let near = last.is_some_and(|l| (l[0] - q[0]).hypot(l[1] - q[1]) < 0.5);
        if near && i + 1 < points.len() {
            continue;
        }
        let _ = write!(coords, "{:.1},{:.1} ", q[0], q[1]);
        last = Some(q);
    }
    let _ = writeln!(
        svg,
        r#"<polyline fill="none" stroke-linejoin="round" stroke-linecap="round" {style} points="{}"/>"#,
        coords.trim_end()
    );
}

/// Marks where the estimate starts (hollow) and ends (filled).
fn draw_endpoints(svg: &mut String, view: &SvgView, trajectory: &[[f64; 2]]) {
    let (Some(first), Some(last)) = (trajectory.first(), trajectory.last()) else {
        return;
    };
    let hollow = format!(
        r#"fill="white" stroke="{ESTIMATE}" stroke-width="{:.2}""#,
        2.0 * view.u
    );
    circle(svg, view.px(*first), 5.0 * view.u, &hollow);
    circle(
        svg,
        view.px(*last),
        4.5 * view.u,
        &format!(r#"fill="{ESTIMATE}""#),
    );
}

/// A circle of radius `r` around the canvas point `at` (pixels), painted by `paint` (its
/// fill and stroke attributes).
fn circle(svg: &mut String, [x, y]: [f64; 2], r: f64, paint: &str) {
    let _ = writeln!(
        svg,
        r#"<circle cx="{x:.1}" cy="{y:.1}" r="{r:.1}" {paint}/>"#
    );
}

/// A map corner: a dot at the tip with a tick behind it, so the glyph reads as an arrow
/// along the heading (which points towards the tip) ending at the corner.
fn map_corner_glyph(svg: &mut String, u: f64, at: [f64; 2], heading: f64) {
    let len = 17.0 * u;
    let (s, c) = heading.sin_cos();
    // Canvas y is down: a world direction (c, s) is (c, -s) on the canvas.
    let tail = [at[0] - len * c, at[1] + len * s];
    let _ = writeln!(
        svg,
        r#"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{MAP_CORNER}" stroke-width="{:.2}" stroke-linecap="round"/>"#,
        tail[0],
        tail[1],
        at[0],
        at[1],
        2.0 * u
    );
    let paint = format!(
        r#"fill="{MAP_CORNER}" stroke="white" stroke-width="{:.2}""#,
        0.8 * u
    );
    circle(svg, at, 3.6 * u, &paint);
}

fn draw_header(svg: &mut String, input: &SvgInput<'_>) {
    let _ = writeln!(
        svg,
        r##"<text x="{MARGIN}" y="28" font-size="19" font-weight="bold" fill="#202020">{}</text>"##,
        escape(input.title)
    );
    for (i, line) in input.subtitle.iter().enumerate() {
        let _ = writeln!(
            svg,
            r##"<text x="{MARGIN}" y="{:.0}" font-size="13.5" fill="#4a4a4a">{}</text>"##,
            51.0 + 19.0 * i as f64,
            escape(line)
        );
    }
}

/// The scale bar on the left of the footer, the legend after it, the note under both.
fn draw_footer(svg: &mut String, view: &SvgView, input: &SvgInput<'_>, top: f64) {
    let y = top + 34.0;
    if !input.note.is_empty() {
        let _ = writeln!(
            svg,
            r##"<text x="{MARGIN}" y="{:.1}" font-size="11.5" fill="#777777">{}</text>"##,
            top + 64.0,
            escape(input.note)
        );
    }
    let metres = nice_length(0.2 * view.map_w / view.k);
    let bar = metres * view.k;
    let x = MARGIN;
    let _ = writeln!(
        svg,
        r##"<path d="M{x:.1} {:.1}v6h{bar:.1}v-6" fill="none" stroke="#202020" stroke-width="1.5"/>"##,
        y - 6.0
    );
    let _ = writeln!(
        svg,
        r##"<text x="{:.1}" y="{:.1}" font-size="13" text-anchor="middle" fill="#202020">{}</text>"##,
        x + bar / 2.0,
        y - 10.0,
        scale_label(metres)
    );

    let mut cursor = x + bar + 48.0;
    let mut item = |svg: &mut String, label: &str, glyph: &dyn Fn(&mut String, f64, f64)| {
        glyph(svg, cursor, y - 4.0);
        let _ = writeln!(
            svg,
            r##"<text x="{:.1}" y="{:.1}" font-size="13" fill="#303030">{}</text>"##,
            cursor + 30.0,
            y,
            escape(label)
        );
        // An estimate of the label's width; exact metrics would need the font.
        cursor += 30.0 + 7.4 * label.chars().count() as f64 + 26.0;
    };
    if !input.cells.is_empty() {
        item(
            svg,
            "occupancy grid (free, unknown, occupied)",
            &|svg, x, y| {
                let _ = writeln!(
                    svg,
                    r##"<rect x="{:.1}" y="{:.1}" width="8" height="8" fill="{FREE_CELL}" stroke="#bbbbbb" stroke-width="0.5"/><rect x="{:.1}" y="{:.1}" width="8" height="8" fill="{UNKNOWN_CELL}"/><rect x="{:.1}" y="{:.1}" width="8" height="8" fill="{OCCUPIED_CELL}"/>"##,
                    x - 6.0,
                    y - 4.0,
                    x + 3.0,
                    y - 4.0,
                    x + 12.0,
                    y - 4.0
                );
            },
        );
    }
    if !input.trajectory.is_empty() {
        item(svg, "estimate", &|svg, x, y| {
            let _ = writeln!(
                svg,
                r#"<path d="M{x:.1} {y:.1}h24" stroke="{ESTIMATE}" stroke-width="2.2"/>"#
            );
        });
    }
    if !input.ground_truth.is_empty() {
        item(svg, "ground truth", &|svg, x, y| {
            let _ = writeln!(
                svg,
                r#"<path d="M{x:.1} {y:.1}h24" stroke="{TRUTH}" stroke-opacity="0.55" stroke-width="6"/>"#
            );
        });
    }
    if !input.dead_reckoning.is_empty() {
        item(svg, "dead reckoning", &|svg, x, y| {
            let _ = writeln!(
                svg,
                r#"<path d="M{x:.1} {y:.1}h24" stroke="{DEAD_RECKONING}" stroke-width="1.6" stroke-dasharray="7 4"/>"#
            );
        });
    }
    if !input.map_corners.is_empty() {
        item(svg, "map corner", &|svg, x, y| {
            map_corner_glyph(svg, 1.0, [x + 20.0, y], 0.0);
        });
    }
    if !input.true_corners.is_empty() {
        item(svg, "true corner", &|svg, x, y| {
            let _ = writeln!(
                svg,
                r#"<circle cx="{:.1}" cy="{y:.1}" r="6" fill="none" stroke="{TRUE_CORNER}" stroke-width="1.5"/>"#,
                x + 12.0
            );
        });
    }
}

/// The largest 1, 2 or 5 times a power of ten not above `target` metres.
fn nice_length(target: f64) -> f64 {
    if !(target > 0.0 && target.is_finite()) {
        return 1.0;
    }
    let power = 10_f64.powf(target.log10().floor());
    [5.0, 2.0, 1.0]
        .into_iter()
        .map(|m| m * power)
        .find(|l| *l <= target * (1.0 + 1e-9))
        .unwrap_or(power)
}

fn scale_label(metres: f64) -> String {
    if metres >= 1000.0 {
        format!("{} km", metres / 1000.0)
    } else if metres >= 1.0 {
        format!("{metres:.0} m")
    } else if metres >= 0.01 {
        format!("{:.0} cm", metres * 100.0)
    } else {
        format!("{:.0} mm", metres * 1000.0)
    }
}

/// Escapes text for an SVG text node.
fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for ch in text.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            _ => out.push(ch),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scale_bar_lengths_are_round() {
        assert_eq!(nice_length(3.7), 2.0);
        assert_eq!(nice_length(7.0), 5.0);
        assert_eq!(nice_length(10.0), 10.0);
        assert!((nice_length(0.3) - 0.2).abs() < 1e-12);
        assert_eq!(scale_label(0.2), "20 cm");
        assert_eq!(scale_label(5.0), "5 m");
    }

    #[test]
    fn runs_merge_and_move_relatively() {
        let cells = [[0, 0], [1, 0], [2, 0], [5, 0], [1, 2]].map(|index| GridCell {
            index,
            occupied: true,
        });
        assert_eq!(
            run_path(cells.iter()),
            "M0 0h3v1h-3zm5 0h1v1h-1zm-4 2h1v1h-1z"
        );
    }
}
