//! The read limit (its own test binary: the limit is process-wide). A file larger than the limit,
//! or a device that never ends (a mesh path linked to /dev/zero grew to 23 GB), is an error
//! naming the file; a file within it reads as before.

use rfta_io::{read_mesh, set_read_limit};

#[test]
fn reads_stop_at_the_limit_with_a_clear_error() {
    let dir = std::env::temp_dir().join(format!("rfta-read-limit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let small = dir.join("tri.obj");
    std::fs::write(&small, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").expect("obj");
    let mut big = String::new();
    for i in 0..20_000 {
        big += &format!("v {i} 0 0\n");
    }
    big += "f 1 2 3\n";
    let large = dir.join("big.obj");
    std::fs::write(&large, &big).expect("obj");
    set_read_limit(64 * 1024);
    assert_eq!(read_mesh(&small).expect("within the limit").n_faces(), 1);
    let e = read_mesh(&large).expect_err("over the limit").to_string();
    assert!(
        e.contains("big.obj") && e.contains("more than the 65536 bytes"),
        "{e}"
    );
    #[cfg(unix)]
    {
        let zero = dir.join("zero.obj");
        std::os::unix::fs::symlink("/dev/zero", &zero).expect("link");
        let e = read_mesh(&zero)
            .expect_err("a device that goes on")
            .to_string();
        assert!(e.contains("it goes on"), "{e}");
    }
    let _ = std::fs::remove_dir_all(dir);
}
