//! Tests of `rfta batch`: shards, the arguments and figures of each row, bad row columns.

use super::*;

#[test]
fn shards_cover_every_row_once() {
    for count in 1..7 {
        for row in 0..50 {
            let owners = (0..count)
                .filter(|&index| Shard { index, count }.takes(row))
                .count();
            assert_eq!(owners, 1, "row {row} of {count} shards");
        }
    }
    assert!(parse_shard("3/3").is_err());
    assert!(parse_shard("1/0").is_err());
    assert_eq!(parse_shard("2/5"), Ok(Shard { index: 2, count: 5 }));
}

/// A row's clamp and preset replace the command line's, never repeat them (clap refuses an
/// option given twice).
#[test]
fn a_rows_clamp_and_preset_replace_the_command_lines() {
    use clap::Parser;
    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: Args,
    }
    let cli = Cli::try_parse_from(["rfta", "m.csv", "--clamp", "0.5", "--preset", "paper"])
        .expect("options");
    let row = row_args(None, Some("0.25".into()), Some("fast".into())).expect("row");
    let mut args = cli.args.checks.to_args(row.clamp);
    args.extend(cli.args.tuning.to_args(row.preset));
    let count = |flag: &str| args.iter().filter(|a| *a == flag).count();
    assert_eq!((count("--clamp"), count("--preset")), (1, 1));
    assert!(args.windows(2).any(|w| w == ["--clamp", "0.25"]));
    assert!(args.windows(2).any(|w| w == ["--preset", "fast"]));
    // Without row values, the command line's.
    let args = cli.args.checks.to_args(None);
    assert!(args.windows(2).any(|w| w == ["--clamp", "0.5"]));
}

/// Every `reconstruct` option of `Checks` and `Tuning` reaches the rows: set them all on
/// the command line and `to_args` gives each back (an option added to either and forgotten in
/// its `to_args` fails here).
#[test]
fn every_reconstruct_option_reaches_the_rows() {
    use clap::{Args as _, Parser};
    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: Args,
    }
    let cli = Cli::try_parse_from([
        "rfta",
        "m.csv",
        "--clamp",
        "0.5",
        "--no-check",
        "--max-memory",
        "2G",
        "--preset",
        "paper",
        "--iters",
        "4",
        "--max-points",
        "5",
        "--seed",
        "9",
        "--gpu",
        "on",
        "--min-island",
        "0.25",
        "--owner-band",
        "2",
        "--raster-res",
        "64",
        "--depth",
        "7",
        "--genus",
        "0",
        "--keep-cavities",
        "--keep-thin-handles",
        "--initial",
        "raster",
        "--field",
        "level-set",
        "--no-simplify",
        "--simplify-tolerance",
        "0.1",
        "--faces",
        "500",
    ])
    .expect("options");
    let mut given: Vec<String> = cli.args.checks.to_args(None);
    given.extend(cli.args.tuning.to_args(None));
    let flags: std::collections::BTreeSet<String> = given
        .iter()
        .filter_map(|a| a.strip_prefix("--"))
        .map(String::from)
        .collect();
    let declared = Tuning::augment_args(Checks::augment_args(clap::Command::new("t")));
    let all: std::collections::BTreeSet<String> = declared
        .get_arguments()
        .filter_map(|a| a.get_long().map(String::from))
        .collect();
    assert_eq!(flags, all);
    // And the values are the ones given.
    for pair in [
        ["--rounds", "4"],
        ["--preset", "paper"],
        ["--max-memory", "2147483648B"],
        ["--faces", "500"],
        ["--simplify-tolerance", "0.1"],
    ] {
        assert!(given.windows(2).any(|w| w == pair), "{pair:?} in {given:?}");
    }
    // Read back, they make the same parameters.
    let again = Cli::try_parse_from(
        ["rfta".to_string(), "m.csv".into()]
            .into_iter()
            .chain(given),
    )
    .expect("options");
    let params = |c: &Cli| c.args.tuning.params().expect("valid");
    assert_eq!(params(&again), params(&cli));
    assert_eq!(params(&cli).rounds, Some(4));
    assert_eq!(params(&cli).spsr_depth, Some(7));
}

/// The status columns are figures of the report `reconstruct --report` writes (its
/// [`rfta::Report`] and the mesh's size), by the same names.
#[test]
fn the_status_figures_are_report_figures() {
    let report = serde_json::to_value(rfta::Report::default()).expect("serializes");
    for f in FIGURES {
        assert!(
            report.get(f).is_some() || ["vertices", "faces"].contains(&f),
            "{f} is no figure of the report"
        );
    }
}

#[test]
fn bad_row_columns_are_reasons_not_errors() {
    assert!(row_args(Some("0 0 0 1 1".into()), None, None).is_err());
    assert!(row_args(None, Some("-1".into()), None).is_err());
    assert!(row_args(None, None, Some("fastest".into())).is_err());
    let row = row_args(Some("-1 -1 -1 1 1 1".into()), None, Some("Fast".into()));
    let row = row.expect("a good row");
    assert_eq!(row.args, ["--bounds=-1,-1,-1,1,1,1"]);
    assert!(matches!(row.preset, Some(Preset::Fast)));
}

/// What a writer killed mid-record left (a last line without its line break) is cut off before
/// the next record, so the two are never glued into one line; a complete line that is not a
/// record is an error naming its line, never dropped.
#[test]
fn a_cut_short_record_is_cut_off_and_a_bad_record_named() {
    let dir = std::env::temp_dir().join(format!("rfta-status-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("dir");
    let path = dir.join("st.csv");
    let record = |row: usize, status: Status| StatusRow {
        row,
        input: format!("i{row}.npy"),
        output: format!("o{row}.obj"),
        status,
        seconds: 1.5,
        message: String::new(),
        figures: vec![String::new(); FIGURES.len()],
    };
    let mut file = StatusFile::open(&path).expect("new file");
    file.append(&record(0, Status::Ok)).expect("append");
    drop(file);
    let whole = std::fs::read_to_string(&path).expect("status");
    std::fs::write(&path, format!("{whole}1,i1.npy,o1.o")).expect("cut short");
    let mut file = StatusFile::open(&path).expect("reopen");
    file.append(&record(2, Status::Failed)).expect("append");
    let rows = read_status(&path).expect("read");
    assert_eq!(
        rows.iter().map(|r| (r.row, r.status)).collect::<Vec<_>>(),
        [(0, Status::Ok), (2, Status::Failed)]
    );
    assert_eq!(
        std::fs::read_to_string(&path)
            .expect("status")
            .lines()
            .count(),
        3
    );
    let text = std::fs::read_to_string(&path).expect("status");
    std::fs::write(&path, text.replace(",failed,1.500,", ",FAILED,1.500,")).expect("edit");
    let e = read_status(&path).expect_err("a bad record").to_string();
    assert!(e.contains("line 3") && e.contains("\"FAILED\""), "{e}");
    // A file another shard has just created, before its header (hostile test E5 read it then
    // and stopped on "no header line"), and one whose header a kill cut short: no records.
    std::fs::write(&path, "").expect("empty");
    assert!(read_status(&path).expect("empty file").is_empty());
    std::fs::write(&path, "row,input,out").expect("cut header");
    assert!(read_status(&path).expect("cut header").is_empty());
    let _ = std::fs::remove_dir_all(dir);
}
