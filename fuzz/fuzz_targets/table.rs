//! CSV tables (batch manifests and status files): any bytes give a table or an error, and every
//! row's fields come back from the line `join_csv` makes of them.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use rfta_io::table::{decode_table, join_csv, split_csv};

fuzz_target!(|data: &[u8]| {
    let Ok(table) = decode_table(data, Path::new("manifest.csv")) else {
        return;
    };
    for row in &table.rows {
        for name in &table.columns {
            let _ = table.get(row, name);
        }
        if !row.fields.iter().any(|f| f.contains('\r')) {
            assert_eq!(split_csv(&join_csv(&row.fields)), row.fields);
        }
    }
});
