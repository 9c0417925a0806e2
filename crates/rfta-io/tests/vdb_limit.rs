//! The memory a level set takes once made dense is checked against the process's limit
//! (`rfta_io::set_read_limit`) from the tree's topology, before the values are read or the box
//! allocated (hostile test E2: a 5.9 MB file asked for 8 GB and aborted). Its own test binary:
//! the limit is process-wide.

use std::path::Path;

#[test]
fn a_level_set_larger_than_the_limit_once_dense_is_refused_before_allocating() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vdb/box.vdb");
    let size = std::fs::metadata(&path).expect("test data").len();
    // The file just fits; its values as read (a leaf of 512 values for each 8^3 block of the
    // band) and its dense box (8 bytes a voxel) do not.
    rfta_io::set_read_limit(size);
    for e in [
        rfta_io::read_sdf(&path, None)
            .expect_err("refused")
            .to_string(),
        rfta_io::peek_sdf_len(&path, None)
            .expect_err("refused")
            .to_string(),
    ] {
        assert!(
            e.contains("makes a dense box") && e.contains("may take"),
            "{e}"
        );
    }
    rfta_io::set_read_limit(u64::MAX);
    assert!(rfta_io::read_sdf(&path, None).is_ok());
}
