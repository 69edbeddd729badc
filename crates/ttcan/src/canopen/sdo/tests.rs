use super::super::frame::{Frame, Frames};
use super::super::ProtocolError;
use super::*;

/// A dictionary of one 4-byte value 0x2000:0 and one string 0x1008:0 (up to 40 bytes).
struct Dict {
    word: u32,
    text: SdoData,
}

impl SdoTarget for Dict {
    fn sdo_read(&mut self, index: u16, sub: u8, out: &mut [u8; SDO_BUFFER]) -> Result<usize, u32> {
        match (index, sub) {
            (0x2000, 0) => {
                out[..4].copy_from_slice(&self.word.to_le_bytes());
                Ok(4)
            }
            (0x1008, 0) => {
                out[..self.text.len].copy_from_slice(self.text.bytes());
                Ok(self.text.len)
            }
            (0x2000 | 0x1008, _) => Err(ABORT_NO_SUBINDEX),
            _ => Err(ABORT_NO_OBJECT),
        }
    }
    fn sdo_check_write(&mut self, index: u16, sub: u8) -> Result<(), u32> {
        match (index, sub) {
            (0x2000 | 0x1008, 0) => Ok(()),
            _ => Err(ABORT_NO_OBJECT),
        }
    }
    fn sdo_write(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), u32> {
        match (index, sub) {
            (0x2000, 0) if data.len() == 4 => {
                self.word = u32::from_le_bytes([data[0], data[1], data[2], data[3]]);
                Ok(())
            }
            (0x2000, 0) => Err(ABORT_LENGTH),
            (0x1008, 0) if data.len() <= 40 => {
                self.text = SdoData::from_bytes(data).unwrap();
                Ok(())
            }
            (0x1008, 0) => Err(ABORT_LENGTH_HIGH),
            _ => Err(ABORT_NO_OBJECT),
        }
    }
}

/// Runs `job` from a client against a server until it completes.
fn run(job: SdoJob, dict: &mut Dict) -> Result<SdoOutcome, SdoError> {
    let mut c = SdoClient::new(5, 3).unwrap();
    let mut s = SdoServer::new();
    let mut f = c.start(job).unwrap();
    for _ in 0..100 {
        let (_, req) = SdoRequest::decode(&f).unwrap();
        let resp = s.serve(&req, dict).unwrap().encode(5).unwrap();
        let mut out = Frames::new();
        if let Some(r) = c.on_frame(&resp, &mut out) {
            assert!(!s.busy() || r.is_err());
            return r;
        }
        f = out.as_slice()[0];
    }
    panic!("transfer did not end");
}

#[test]
fn requests_and_responses_round_trip_for_every_size() {
    for size in 1..=4u8 {
        let value = 0xA1B2_C3D4u32 & if size == 4 { u32::MAX } else { (1 << (8 * size)) - 1 };
        let req = SdoRequest::Download {
            index: 0x6060,
            sub: 0,
            size,
            value,
        };
        let f = req.encode(3).unwrap();
        assert_eq!(f.id(), 0x603);
        assert_eq!(SdoRequest::decode(&f).unwrap(), (3, req));
        let resp = SdoResponse::Uploaded {
            index: 0x6064,
            sub: 0,
            size,
            value,
        };
        assert_eq!(SdoResponse::decode(&resp.encode(3).unwrap()).unwrap(), (3, resp));
    }
    // The well-known command bytes: 4-byte write 0x23, 1-byte write 0x2F, 2-byte upload 0x4B.
    let f = SdoRequest::Download {
        index: 0x1017,
        sub: 0,
        size: 1,
        value: 5,
    }
    .encode(1)
    .unwrap();
    assert_eq!(f.data()[..4], [0x2F, 0x17, 0x10, 0x00]);
    // segmented: initiate 0x21 with the size, last segment of 3 bytes 0x09 | toggle 0x10
    let f = SdoRequest::InitiateDownload {
        index: 0x1008,
        sub: 0,
        size: Some(10),
    }
    .encode(1)
    .unwrap();
    assert_eq!(f.data(), &[0x21, 0x08, 0x10, 0, 10, 0, 0, 0]);
    let seg = Segment {
        toggle: true,
        len: 3,
        data: [1, 2, 3, 0, 0, 0, 0],
        last: true,
    };
    let f = SdoRequest::DownloadSegment(seg).encode(1).unwrap();
    assert_eq!(f.data(), &[0x19, 1, 2, 3, 0, 0, 0, 0]);
    assert_eq!(SdoRequest::decode(&f).unwrap().1, SdoRequest::DownloadSegment(seg));
    let f = SdoResponse::UploadSegment(seg).encode(1).unwrap();
    assert_eq!(SdoResponse::decode(&f).unwrap().1, SdoResponse::UploadSegment(seg));
}

#[test]
fn segmented_upload_and_download_of_a_string_through_client_and_server() {
    let mut d = Dict {
        word: 7,
        text: SdoData::from_bytes(b"ttdrive-sim virtual CiA 402 drive").unwrap(),
    };
    let r = run(SdoJob::Read { index: 0x1008, sub: 0 }, &mut d).unwrap();
    let SdoOutcome::Read { data, .. } = r else { panic!() };
    assert_eq!(data.bytes(), b"ttdrive-sim virtual CiA 402 drive");
    // lengths around the segment size, 5..=40 bytes
    for n in [5usize, 7, 8, 14, 15, 40] {
        let text: Vec<u8> = (0..n as u8).map(|k| b'a' + k % 26).collect();
        let job = SdoJob::Write {
            index: 0x1008,
            sub: 0,
            data: SdoData::from_bytes(&text).unwrap(),
        };
        assert_eq!(run(job, &mut d).unwrap(), SdoOutcome::Written { index: 0x1008, sub: 0 });
        assert_eq!(d.text.bytes(), &text[..]);
        let SdoOutcome::Read { data, .. } = run(SdoJob::Read { index: 0x1008, sub: 0 }, &mut d).unwrap() else {
            panic!()
        };
        assert_eq!(data.bytes(), &text[..]);
    }
    let long = SdoJob::Write {
        index: 0x1008,
        sub: 0,
        data: SdoData::from_bytes(&[b'x'; 41]).unwrap(),
    };
    assert_eq!(
        run(long, &mut d),
        Err(SdoError::Aborted {
            index: 0x1008,
            sub: 0,
            code: ABORT_LENGTH_HIGH
        })
    );
    assert_eq!(
        run(SdoJob::write_int(0x2000, 0, 4, 0xDEAD_BEEF), &mut d).unwrap(),
        SdoOutcome::Written { index: 0x2000, sub: 0 }
    );
    assert_eq!(d.word, 0xDEAD_BEEF);
    assert!(matches!(
        run(SdoJob::Read { index: 0x3000, sub: 0 }, &mut d),
        Err(SdoError::Aborted {
            code: ABORT_NO_OBJECT,
            ..
        })
    ));
}

proptest::proptest! {
    /// Any value of 1–40 bytes goes through client and server and reads back the same.
    #[test]
    fn any_string_round_trips_through_client_and_server(bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 1..=40)) {
        let mut d = Dict { word: 0, text: SdoData::default() };
        let job = SdoJob::Write { index: 0x1008, sub: 0, data: SdoData::from_bytes(&bytes).unwrap() };
        proptest::prop_assert_eq!(run(job, &mut d).unwrap(), SdoOutcome::Written { index: 0x1008, sub: 0 });
        let SdoOutcome::Read { data, .. } = run(SdoJob::Read { index: 0x1008, sub: 0 }, &mut d).unwrap() else {
            panic!("not a read")
        };
        proptest::prop_assert_eq!(data.bytes(), &bytes[..]);
    }
}

#[test]
fn server_aborts_block_transfers_wrong_toggles_and_stray_segments() {
    let mut d = Dict {
        word: 0,
        text: SdoData::default(),
    };
    let mut s = SdoServer::new();
    for upload in [true, false] {
        let r = s.serve(
            &SdoRequest::Block {
                upload,
                index: 0x1008,
                sub: 0,
            },
            &mut d,
        );
        assert_eq!(
            r,
            Some(SdoResponse::Abort {
                index: 0x1008,
                sub: 0,
                code: ABORT_COMMAND
            })
        );
    }
    // a block download request as python-canopen sends it: 0xC6
    let f = Frame::new(0x605, &[0xC6, 0x08, 0x10, 0, 20, 0, 0, 0]).unwrap();
    assert!(matches!(
        SdoRequest::decode(&f).unwrap().1,
        SdoRequest::Block { upload: false, .. }
    ));
    // segment without initiation
    let r = s.serve(&SdoRequest::UploadSegment { toggle: false }, &mut d);
    assert!(matches!(
        r,
        Some(SdoResponse::Abort {
            code: ABORT_COMMAND,
            ..
        })
    ));
    // toggle error
    s.serve(
        &SdoRequest::InitiateDownload {
            index: 0x1008,
            sub: 0,
            size: Some(10),
        },
        &mut d,
    );
    let seg = Segment {
        toggle: true,
        len: 7,
        ..Segment::default()
    };
    let r = s.serve(&SdoRequest::DownloadSegment(seg), &mut d);
    assert!(matches!(r, Some(SdoResponse::Abort { code: ABORT_TOGGLE, .. })));
    assert!(!s.busy());
    // a command specifier 7 is not SDO
    let f = Frame::new(0x605, &[0xE0, 0, 0, 0, 0, 0, 0, 0]).unwrap();
    assert_eq!(SdoRequest::decode(&f), Err(ProtocolError::BadCommand(0xE0)));
}

#[test]
fn client_matches_response_to_request_and_times_out() {
    let mut out = Frames::new();
    let mut c = SdoClient::new(2, 3).unwrap();
    let job = SdoJob::Read { index: 0x6041, sub: 0 };
    assert!(c.start(job).is_some());
    assert!(c.start(job).is_none(), "one transfer at a time");
    let wrong = SdoResponse::Downloaded { index: 0x6040, sub: 0 }.encode(2).unwrap();
    assert_eq!(
        c.on_frame(&wrong, &mut out),
        Some(Err(SdoError::OutOfSequence { index: 0x6041, sub: 0 }))
    );
    assert!(c.start(job).is_some());
    let other_node = SdoResponse::Downloaded { index: 0x6041, sub: 0 }.encode(4).unwrap();
    assert_eq!(c.on_frame(&other_node, &mut out), None);
    for _ in 0..3 {
        assert_eq!(c.tick(), None);
    }
    assert!(matches!(c.tick(), Some(SdoError::Timeout { .. })));
    assert_eq!(c.timeouts, 1);
    assert!(!c.busy());
}
