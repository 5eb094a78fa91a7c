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
