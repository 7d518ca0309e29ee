//! Prints the column table of results/README.md (used by scripts/update-columns.sh).
fn main() {
    print!("{}", schema::markdown());
}
