//! The committed albedo tables (`data/albedo/`) must be what `albedo_table::generate`
//! integrates today. Checking every cell would take minutes, so each table's first and
//! last cells and 40 cells at pseudo-random positions are recomputed and must match the
//! committed codes to one quantization step (libm's last bit may differ between
//! machines). Regenerate every table with
//! `GLINT_BLESS=1 cargo test --release --test albedo_tables` (minutes on 2 cores) and
//! commit `data/albedo/`; `GLINT_BLESS=<text>` regenerates only the tables whose file
//! name contains `<text>` (`disney`: the Disney specular and clearcoat tables).

use glint::albedo_table::Table;
use glint::albedo_table::disney::{ClearcoatTable, SpecularAnisotropicTable, SpecularTable};
use glint::albedo_table::generate::{cell, generate, quantize};
use std::path::PathBuf;

fn path(table: Table) -> PathBuf {
    data(&table.file_name())
}

fn data(file: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("data/albedo")
        .join(file)
}

/// The Disney lobes' tables: file, cells, channels, generator, one cell.
type DisneyTable = (
    &'static str,
    usize,
    usize,
    fn() -> Vec<u8>,
    fn(usize) -> Vec<f64>,
);
const DISNEY: [DisneyTable; 3] = [
    (
        SpecularTable::FILE,
        SpecularTable::CELLS,
        SpecularTable::CHANNELS,
        SpecularTable::generate,
        SpecularTable::cell,
    ),
    (
        SpecularAnisotropicTable::FILE,
        SpecularAnisotropicTable::CELLS,
        SpecularAnisotropicTable::CHANNELS,
        SpecularAnisotropicTable::generate,
        SpecularAnisotropicTable::cell,
    ),
    (
        ClearcoatTable::FILE,
        ClearcoatTable::CELLS,
        ClearcoatTable::CHANNELS,
        ClearcoatTable::generate,
        ClearcoatTable::cell,
    ),
];

/// Cells to recompute: both ends and 40 from a fixed-seed LCG.
fn sampled_cells(cells: usize) -> Vec<usize> {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut out = vec![0, cells - 1];
    out.extend((0..40).map(|_| {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 33) as usize % cells
    }));
    out
}

#[test]
fn committed_tables_match_their_generator() {
    if let Some(bless) = std::env::var_os("GLINT_BLESS") {
        let only = bless.to_string_lossy().into_owned();
        for table in Table::all() {
            if only != "1" && !table.file_name().contains(&only) {
                continue;
            }
            let start = std::time::Instant::now();
            std::fs::write(path(table), generate(table)).expect("write table");
            eprintln!("{}: {:?}", table.file_name(), start.elapsed());
        }
    }
    let mut failures = Vec::new();
    for table in Table::all() {
        let bytes = std::fs::read(path(table)).unwrap_or_default();
        let channels = table.channels();
        if bytes.len() != 2 * table.cells() * channels {
            failures.push(format!(
                "{}: {} bytes, the layout needs {}",
                table.file_name(),
                bytes.len(),
                2 * table.cells() * channels
            ));
            continue;
        }
        for index in sampled_cells(table.cells()) {
            for (k, value) in cell(table, index).into_iter().enumerate() {
                let at = 2 * (index * channels + k);
                let committed = u16::from_le_bytes([bytes[at], bytes[at + 1]]);
                if committed.abs_diff(quantize(value)) > 1 {
                    failures.push(format!(
                        "{} cell {index} channel {k}: committed {committed}, generated {}",
                        table.file_name(),
                        quantize(value)
                    ));
                }
            }
        }
    }
    for (file, cells, channels, generate, cell) in DISNEY {
        if let Some(bless) = std::env::var_os("GLINT_BLESS")
            && (bless == "1" || file.contains(&*bless.to_string_lossy()))
        {
            let start = std::time::Instant::now();
            std::fs::write(data(file), generate()).expect("write table");
            eprintln!("{file}: {:?}", start.elapsed());
        }
        let bytes = std::fs::read(data(file)).unwrap_or_default();
        if bytes.len() != 2 * cells * channels {
            failures.push(format!(
                "{file}: {} bytes, the layout needs {}",
                bytes.len(),
                2 * cells * channels
            ));
            continue;
        }
        for index in sampled_cells(cells) {
            for (k, value) in cell(index).into_iter().enumerate() {
                let at = 2 * (index * channels + k);
                let committed = u16::from_le_bytes([bytes[at], bytes[at + 1]]);
                if committed.abs_diff(quantize(value)) > 1 {
                    failures.push(format!(
                        "{file} cell {index} channel {k}: committed {committed}, generated {}",
                        quantize(value)
                    ));
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "stale albedo tables (regenerate with GLINT_BLESS=1 cargo test --release --test \
         albedo_tables):\n{}",
        failures.join("\n")
    );
}
