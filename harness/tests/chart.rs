//! The error-against-time chart as a user opens it: a PNG of the stated size and an SVG
//! whose legend names every curve (the text is drawn with the vendored font).

use harness::chart::{CHART_SIZE, Series, write_loglog_chart};

#[test]
fn chart_is_written_as_png_and_svg_with_every_legend_name() {
    let dir = std::env::temp_dir().join(format!("ppm-chart-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let stem = dir.join("error-vs-time");
    let curve = |k: f64| {
        (1..=12)
            .map(|i| (0.25 * f64::from(i), k / f64::from(i).sqrt()))
            .collect()
    };
    let series = [
        Series {
            name: "restart",
            colour: [0.8, 0.1, 0.1],
            points: curve(0.3),
            dashed: false,
        },
        Series {
            name: "difference",
            colour: [0.9, 0.6, 0.0],
            points: curve(0.1),
            dashed: false,
        },
        Series {
            name: "perfect",
            colour: [0.55; 3],
            points: curve(0.05),
            dashed: true,
        },
    ];
    write_loglog_chart(
        &stem,
        "cornell-box: error after the move",
        "seconds since the move",
        "relative rmse",
        &series,
    )
    .unwrap();
    let png = std::fs::File::open(dir.join("error-vs-time.png")).unwrap();
    let info = png::Decoder::new(std::io::BufReader::new(png))
        .read_info()
        .unwrap();
    assert_eq!((info.info().width, info.info().height), CHART_SIZE);
    let svg = std::fs::read_to_string(dir.join("error-vs-time.svg")).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    // Every piece of text the SVG draws, without its markup.
    let texts: Vec<&str> = svg
        .split("<text")
        .skip(1)
        .filter_map(|t| Some(t.split_once('>')?.1.split_once("</text>")?.0.trim()))
        .collect();
    for s in &series {
        assert!(
            texts.contains(&s.name),
            "the legend lacks {}: {texts:?}",
            s.name
        );
    }
    for text in [
        "cornell-box: error after the move",
        "seconds since the move",
        "relative rmse",
    ] {
        assert!(texts.contains(&text), "the SVG lacks {text:?}");
    }
    // Ticks are labelled between decades on this short axis (0.25 .. 3 seconds).
    for tick in ["0.2", "0.5", "1", "2", "5"] {
        assert!(texts.contains(&tick), "no tick labelled {tick}: {texts:?}");
    }
}

/// The report's chart names the perfect-compensation bound only where it was measured (it
/// needs a restart run): a run of local mode alone draws no empty "perfect" entry.
#[test]
fn an_unmeasured_perfect_bound_is_left_off_the_report_chart() {
    use harness::error_report::{Measurement, ModeRun, chart};
    use ppm_core::params::MoveMode;
    let dir = std::env::temp_dir().join(format!("ppm-chart-perfect-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let measurements = (1..=8)
        .map(|i| Measurement {
            mode: MoveMode::Local,
            seconds: 0.25 * f64::from(i),
            rel_rmse: 0.1 / f64::from(i).sqrt(),
            kept: 0.08 / f64::from(i).sqrt(),
            reset: 0.06 / f64::from(i).sqrt(),
            passes: i,
        })
        .collect();
    let local = ModeRun {
        mode: MoveMode::Local,
        moves: Vec::new(),
        counts: Default::default(),
        r2_initial: 1.0,
        measurements,
        kept_slope: None,
        brightest_after_move: None,
        brightest_final: None,
        iteration_ms: None,
    };
    let legend = |perfect: &[(f64, f64)]| {
        let stem = dir.join("chart");
        chart(&stem, "cornell-box", std::slice::from_ref(&local), perfect).unwrap();
        std::fs::read_to_string(stem.with_extension("svg")).unwrap()
    };
    let without = legend(&[]);
    let with = legend(&[(0.25, 0.05), (2.0, 0.02)]);
    std::fs::remove_dir_all(&dir).ok();
    assert!(without.contains("local"), "the local curve is not named");
    assert!(!without.contains("perfect"), "an empty bound is named");
    assert!(with.contains("perfect"), "a measured bound is not named");
}
