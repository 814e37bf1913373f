use defmt_decoder::{DecodeError, Table};
fn main() {
    let mut a = std::env::args().skip(1);
    let elf = std::fs::read(a.next().unwrap()).unwrap();
    let bytes = std::fs::read(a.next().unwrap()).unwrap();
    let table = Table::parse(&elf).unwrap().expect(".defmt section");
    let mut dec = table.new_stream_decoder();
    dec.received(&bytes);
    loop {
        match dec.decode() {
            Ok(f) => println!("{}", f.display(true)),
            Err(DecodeError::UnexpectedEof) => break,
            Err(DecodeError::Malformed) => {
                println!("<malformed>");
                if !table.encoding().can_recover() {
                    break;
                }
            }
        }
    }
}
