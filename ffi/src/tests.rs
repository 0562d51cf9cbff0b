extern crate std;
#[test]
fn print_size() {
    std::println!(
        "size {} align {}",
        super::ldcbf_controller_size(),
        super::ldcbf_controller_align()
    );
}
