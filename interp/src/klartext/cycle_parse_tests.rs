//! Tests of the cycle block parser: old and current formats, calls and patterns.

use super::*;

fn parse(text: &str) -> (Stmt, Parser) {
    let mut p = Parser::default();
    let b = p.parse(text.as_bytes()).expect("parses");
    (b.stmt, p)
}

fn words(p: &Parser) -> Vec<(String, Option<Value>, Option<bool>)> {
    p.cycle
        .items
        .iter()
        .map(|it| {
            (
                String::from_utf8_lossy(it.word()).into_owned(),
                it.value,
                it.sign_only,
            )
        })
        .collect()
}

#[test]
fn old_heads_and_sub_blocks() {
    let (s, _) = parse("3 CYCL DEF 7.0 NULLPUNKT");
    assert_eq!(
        s,
        Stmt::CycleDef {
            number: 7,
            sub: Some(0)
        }
    );
    let (s, p) = parse("4 CYCL DEF 7.1  X + 0,5");
    assert_eq!(
        s,
        Stmt::CycleDef {
            number: 7,
            sub: Some(1)
        }
    );
    assert_eq!(words(&p), vec![("X".into(), Some(Value::Num(0.5)), None)]);
    let (_, p) = parse("4 CYCL DEF 7.1 IX-Q7");
    let q7 = ParamRef {
        kind: ParamKind::Q,
        index: 7,
    };
    assert_eq!(
        words(&p),
        vec![(
            "IX".into(),
            Some(Value::Param {
                param: q7,
                negate: true
            }),
            None
        )]
    );
    let (_, p) = parse("5 CYCL DEF 7.1 #3");
    assert_eq!(words(&p), vec![("#".into(), Some(Value::Num(3.0)), None)]);
    let (_, p) = parse("5 CYCL DEF 8.1 X Y");
    assert_eq!(
        words(&p),
        vec![("X".into(), None, None), ("Y".into(), None, None)]
    );
    let (_, p) = parse("5 CYCL DEF 8.1 ");
    assert!(words(&p).is_empty());
    let (_, p) = parse("CYCL DEF 32.2 HSC-MODE:0 TA0,5");
    assert_eq!(
        words(&p),
        vec![
            ("HSC-MODE".into(), Some(Value::Num(0.0)), None),
            ("TA".into(), Some(Value::Num(0.5)), None)
        ]
    );
    let (_, p) = parse("9 CYCL DEF 5.5 F450 DR+");
    assert_eq!(
        words(&p),
        vec![
            ("F".into(), Some(Value::Num(450.0)), None),
            ("DR".into(), None, Some(false))
        ]
    );
    let (_, p) = parse("9 CYCL DEF 1.4 V.ZEIT0");
    assert_eq!(
        words(&p),
        vec![("V.ZEIT".into(), Some(Value::Num(0.0)), None)]
    );
    let (_, p) = parse("9 CYCL DEF 5.1 SET UP-2,000");
    assert_eq!(
        words(&p),
        vec![
            ("SET".into(), None, None),
            ("UP".into(), Some(Value::Num(-2.0)), None)
        ]
    );
    let (_, p) = parse("9 CYCL DEF 14.1 KONTURLABEL1 /2 /3");
    assert_eq!(
        words(&p),
        vec![
            ("KONTURLABEL".into(), Some(Value::Num(1.0)), None),
            ("".into(), Some(Value::Num(2.0)), None),
            ("".into(), Some(Value::Num(3.0)), None)
        ]
    );
}

#[test]
fn current_format_q_values() {
    let text = "7 CYCL DEF 200 BOHREN ~\n    Q200=+2 ;SICHERHEITS-ABST. ~\n    Q201=-Q5 ;TIEFE ~\n    Q206= AUTO ;F ~\n    Q253=MAX\n    Q211=PREDEF ;x";
    let (s, p) = parse(text);
    assert_eq!(
        s,
        Stmt::CycleDef {
            number: 200,
            sub: None
        }
    );
    let q5 = ParamRef {
        kind: ParamKind::Q,
        index: 5,
    };
    let got: Vec<(u32, CycleValue)> = p.cycle.q.iter().map(|e| (e.q, e.value)).collect();
    assert_eq!(
        got,
        vec![
            (200, CycleValue::Val(Value::Num(2.0))),
            (
                201,
                CycleValue::Val(Value::Param {
                    param: q5,
                    negate: true
                })
            ),
            (206, CycleValue::Auto),
            (253, CycleValue::Max),
            (211, CycleValue::Predef),
        ]
    );
}

#[test]
fn calls_and_patterns() {
    let (s, p) = parse("46 CYCL CALL POS  X+Q85  Y+Q86  Z+0 FMAX M3");
    assert_eq!(
        s,
        Stmt::CycleCall {
            kind: CallKind::Pos
        }
    );
    assert!(p.words.axes[0].is_some() && p.words.axes[2].is_some());
    let (s, p) = parse("11 CYCL CALL M");
    assert_eq!(
        s,
        Stmt::CycleCall {
            kind: CallKind::Here
        }
    );
    assert_eq!(p.words.m_count, 0);
    let (s, _) = parse("11 CYCL CALL PAT FMAX M13");
    assert_eq!(
        s,
        Stmt::CycleCall {
            kind: CallKind::Pat
        }
    );
    let (s, p) =
        parse("5 PATTERN DEF ~\n POS1 (X+25 Y+33,5 Z+0) ~\n CIRC1 (X+0 Y+0 D80 START+45 NUM8 Z+0)");
    assert_eq!(s, Stmt::PatternDef);
    assert_eq!(p.cycle.pattern.len(), 2);
    assert_eq!(p.cycle.pattern[1].kind, PatternKind::Circ);
    assert_eq!(p.cycle.pattern[1].get(b"D"), Some(Value::Num(80.0)));
    assert_eq!(p.cycle.pattern[1].get(b"NUM"), Some(Value::Num(8.0)));
    assert_eq!(p.cycle.pattern[0].get(b"Y"), Some(Value::Num(33.5)));
}

#[test]
fn malformed_cycle_blocks_are_errors() {
    let mut p = Parser::default();
    assert!(p.parse(b"1 CYCL XYZ").is_err());
    assert!(p.parse(b"1 CYCL DEF").is_err());
    assert!(p.parse(b"1 CYCL DEF 200 X ~\n Q200=").is_err());
    assert!(p.parse(b"1 PATTERN DEF POS1 (X+1").is_err());
    assert!(p.parse(b"1 CYCL DEF 7.1 X+1 $").is_err());
}

#[test]
fn cycle_numbers_glued_to_def_or_spaced_from_the_sub_block() {
    let head = Stmt::CycleDef {
        number: 9,
        sub: Some(0),
    };
    for text in [
        "4 CYCL DEF9 .0 DWELL TIME",
        "4 CYCL DEF9.0 DWELL TIME",
        "4 CYCL DEF 9 .0 DWELL TIME",
        "4 CYCL DEF  9  .0 DWELL TIME",
    ] {
        assert_eq!(parse(text).0, head, "{text}");
    }
    let (s, p) = parse("5 CYCL DEF9 .1 V.ZEIT1");
    assert_eq!(
        s,
        Stmt::CycleDef {
            number: 9,
            sub: Some(1)
        }
    );
    assert_eq!(
        words(&p),
        vec![("V.ZEIT".into(), Some(Value::Num(1.0)), None)]
    );
    let (s, p) = parse("6 CYCL DEF 7 .1 X+10");
    assert_eq!(
        s,
        Stmt::CycleDef {
            number: 7,
            sub: Some(1)
        }
    );
    assert_eq!(words(&p), vec![("X".into(), Some(Value::Num(10.0)), None)]);
    // the current format glued to DEF
    let (s, _) = parse("7 CYCL DEF200 BOHREN");
    assert_eq!(
        s,
        Stmt::CycleDef {
            number: 200,
            sub: None
        }
    );
}

#[test]
fn a_bad_cycl_block_names_what_it_found() {
    let mut p = Parser::default();
    let e = p.parse(b"1 CYCL DEFINE 7.0").unwrap_err();
    assert_eq!(
        e.error.to_string(),
        "unexpected word 'DEFINE' after CYCL (expected DEF or CALL)"
    );
    assert_eq!(e.pos, 7);
    let e = p.parse(b"1 CYCL").unwrap_err();
    assert_eq!(
        e.error.to_string(),
        "unexpected end of block after CYCL (expected DEF or CALL)"
    );
}
