//! A log-log line chart rendered straight to an image, with a built-in 5x7 pixel font, so
//! reports need no font files or plotting stack.

use ppm_core::image::Image;

/// One curve: name, linear RGB colour, and (x, y) points with x, y > 0.
pub struct Series<'a> {
    /// Legend label.
    pub name: &'a str,
    /// Line colour.
    pub colour: [f32; 3],
    /// Points, in drawing order.
    pub points: Vec<(f64, f64)>,
}

const WIDTH: u32 = 720;
const HEIGHT: u32 = 480;
const LEFT: f64 = 80.0;
const RIGHT: f64 = 20.0;
const TOP: f64 = 40.0;
const BOTTOM: f64 = 60.0;

/// Renders the series on log-log axes with decade ticks, axis labels and a legend.
pub fn loglog_chart(title: &str, x_label: &str, y_label: &str, series: &[Series]) -> Image {
    let mut img = Image::new(WIDTH, HEIGHT);
    img.pixels.iter_mut().for_each(|p| *p = [1.0; 3]);
    let all: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .collect();
    if all.is_empty() {
        text(&mut img, LEFT as i32, 20, title, [0.0; 3]);
        return img;
    }
    let range = |f: fn(&(f64, f64)) -> f64| {
        let lo = all
            .iter()
            .map(f)
            .fold(f64::INFINITY, f64::min)
            .log10()
            .floor();
        let hi = all
            .iter()
            .map(f)
            .fold(f64::NEG_INFINITY, f64::max)
            .log10()
            .ceil();
        (lo, if hi > lo { hi } else { lo + 1.0 })
    };
    let (x0, x1) = range(|p| p.0);
    let (y0, y1) = range(|p| p.1);
    let (pw, ph) = (
        f64::from(WIDTH) - LEFT - RIGHT,
        f64::from(HEIGHT) - TOP - BOTTOM,
    );
    let to_px = |x: f64, y: f64| {
        (
            LEFT + (x.log10() - x0) / (x1 - x0) * pw,
            TOP + (1.0 - (y.log10() - y0) / (y1 - y0)) * ph,
        )
    };
    let grey = [0.8; 3];
    for d in x0 as i32..=x1 as i32 {
        let (px, _) = to_px(10f64.powi(d), 10f64.powi(y0 as i32));
        line(&mut img, (px, TOP), (px, TOP + ph), grey);
        text(
            &mut img,
            px as i32 - 12,
            (TOP + ph) as i32 + 8,
            &format!("1e{d}"),
            [0.0; 3],
        );
    }
    for d in y0 as i32..=y1 as i32 {
        let (_, py) = to_px(10f64.powi(x0 as i32), 10f64.powi(d));
        line(&mut img, (LEFT, py), (LEFT + pw, py), grey);
        text(&mut img, 8, py as i32 - 3, &format!("1e{d}"), [0.0; 3]);
    }
    let black = [0.0; 3];
    line(&mut img, (LEFT, TOP), (LEFT, TOP + ph), black);
    line(&mut img, (LEFT, TOP + ph), (LEFT + pw, TOP + ph), black);
    text(&mut img, LEFT as i32, 14, title, black);
    text(
        &mut img,
        (LEFT + pw / 2.0) as i32 - 3 * x_label.len() as i32,
        HEIGHT as i32 - 22,
        x_label,
        black,
    );
    text(&mut img, 8, TOP as i32 - 16, y_label, black);
    for (k, s) in series.iter().enumerate() {
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .filter(|(x, y)| *x > 0.0 && *y > 0.0)
            .map(|&(x, y)| to_px(x, y))
            .collect();
        for w in pts.windows(2) {
            for offset in [0.0, 1.0] {
                line(
                    &mut img,
                    (w[0].0, w[0].1 + offset),
                    (w[1].0, w[1].1 + offset),
                    s.colour,
                );
            }
        }
        for p in &pts {
            for dy in -2..=2 {
                for dx in -2..=2 {
                    put(&mut img, p.0 as i32 + dx, p.1 as i32 + dy, s.colour);
                }
            }
        }
        let (lx, ly) = (
            LEFT as i32 + pw as i32 - 140,
            TOP as i32 + 10 + 14 * k as i32,
        );
        line(
            &mut img,
            (f64::from(lx), f64::from(ly + 3)),
            (f64::from(lx + 20), f64::from(ly + 3)),
            s.colour,
        );
        text(&mut img, lx + 26, ly, s.name, black);
    }
    img
}

fn put(img: &mut Image, x: i32, y: i32, c: [f32; 3]) {
    if x >= 0 && y >= 0 && (x as u32) < img.width && (y as u32) < img.height {
        img.pixels[(y as u32 * img.width + x as u32) as usize] = c;
    }
}

fn line(img: &mut Image, a: (f64, f64), b: (f64, f64), c: [f32; 3]) {
    let steps = (b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil().max(1.0) as i32;
    for i in 0..=steps {
        let t = f64::from(i) / f64::from(steps);
        put(
            img,
            (a.0 + (b.0 - a.0) * t).round() as i32,
            (a.1 + (b.1 - a.1) * t).round() as i32,
            c,
        );
    }
}

/// Draws `s` with the 5x7 font (6 pixels per character); unknown characters are blank.
fn text(img: &mut Image, x: i32, y: i32, s: &str, c: [f32; 3]) {
    for (i, ch) in s.chars().enumerate() {
        if let Some(rows) = glyph(ch.to_ascii_lowercase()) {
            for (r, row) in rows.iter().enumerate() {
                for col in 0..5 {
                    if row & (0x10 >> col) != 0 {
                        put(img, x + 6 * i as i32 + col, y + r as i32, c);
                    }
                }
            }
        }
    }
}

/// Rows of a 5x7 glyph, most significant of the five bits leftmost.
fn glyph(c: char) -> Option<[u8; 7]> {
    Some(match c {
        '0' => [14, 17, 19, 21, 25, 17, 14],
        '1' => [4, 12, 4, 4, 4, 4, 14],
        '2' => [14, 17, 1, 2, 4, 8, 31],
        '3' => [31, 2, 4, 2, 1, 17, 14],
        '4' => [2, 6, 10, 18, 31, 2, 2],
        '5' => [31, 16, 30, 1, 1, 17, 14],
        '6' => [6, 8, 16, 30, 17, 17, 14],
        '7' => [31, 1, 2, 4, 8, 8, 8],
        '8' => [14, 17, 17, 14, 17, 17, 14],
        '9' => [14, 17, 17, 15, 1, 2, 12],
        'a' => [0, 0, 14, 1, 15, 17, 15],
        'b' => [16, 16, 22, 25, 17, 17, 30],
        'c' => [0, 0, 14, 16, 16, 17, 14],
        'd' => [1, 1, 13, 19, 17, 17, 15],
        'e' => [0, 0, 14, 17, 31, 16, 14],
        'f' => [6, 9, 8, 28, 8, 8, 8],
        'g' => [0, 15, 17, 17, 15, 1, 14],
        'h' => [16, 16, 22, 25, 17, 17, 17],
        'i' => [4, 0, 12, 4, 4, 4, 14],
        'j' => [2, 0, 6, 2, 2, 18, 12],
        'k' => [16, 16, 18, 20, 24, 20, 18],
        'l' => [12, 4, 4, 4, 4, 4, 14],
        'm' => [0, 0, 26, 21, 21, 17, 17],
        'n' => [0, 0, 22, 25, 17, 17, 17],
        'o' => [0, 0, 14, 17, 17, 17, 14],
        'p' => [0, 0, 30, 17, 30, 16, 16],
        'q' => [0, 0, 13, 19, 15, 1, 1],
        'r' => [0, 0, 22, 25, 16, 16, 16],
        's' => [0, 0, 14, 16, 14, 1, 30],
        't' => [8, 8, 28, 8, 8, 9, 6],
        'u' => [0, 0, 17, 17, 17, 19, 13],
        'v' => [0, 0, 17, 17, 17, 10, 4],
        'w' => [0, 0, 17, 17, 21, 21, 10],
        'x' => [0, 0, 17, 10, 4, 10, 17],
        'y' => [0, 0, 17, 17, 15, 1, 14],
        'z' => [0, 0, 31, 2, 4, 8, 31],
        '.' => [0, 0, 0, 0, 0, 12, 12],
        ',' => [0, 0, 0, 0, 12, 4, 8],
        '-' => [0, 0, 0, 31, 0, 0, 0],
        '+' => [0, 4, 4, 31, 4, 4, 0],
        '(' => [2, 4, 8, 8, 8, 4, 2],
        ')' => [8, 4, 2, 2, 2, 4, 8],
        '/' => [0, 1, 2, 4, 8, 16, 0],
        ':' => [0, 12, 12, 0, 12, 12, 0],
        '=' => [0, 0, 31, 0, 31, 0, 0],
        '*' => [0, 17, 10, 4, 10, 17, 0],
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curves_are_drawn_in_their_colours_inside_the_axes() {
        let red = [1.0, 0.0, 0.0];
        let img = loglog_chart(
            "error vs time",
            "seconds",
            "relative rmse",
            &[Series {
                name: "restart",
                colour: red,
                points: vec![(0.5, 0.3), (2.0, 0.1), (8.0, 0.04)],
            }],
        );
        let reds = img.pixels.iter().filter(|p| **p == red).count();
        assert!(reds > 100, "{reds} red pixels");
        // Nothing is drawn in colour outside the plot rectangle but the legend swatch.
        let outside = (0..img.height)
            .flat_map(|y| (0..(LEFT as u32 - 1)).map(move |x| (x, y)))
            .filter(|&(x, y)| img.at(x, y) == red)
            .count();
        assert_eq!(outside, 0);
    }
}
