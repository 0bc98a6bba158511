//! `POST /api/spindle`: the spindle by hand (see [`crate::serve::session::spindle`]).

use super::{ApiError, App, ask};
use crate::serve::session::Command;
use crate::serve::session::spindle::{SpindleDirection, SpindleRequest};
use axum::extract::State;
use axum::http::StatusCode;
use serde::Deserialize;

/// The body: `{"direction": "cw" | "ccw" | "stop", "speed": rpm}` (no speed needed to stop).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Body {
    direction: String,
    speed: Option<f64>,
}

/// The request in `body`, or why it is none (answered with 422).
fn parse(body: &[u8]) -> Result<SpindleRequest, ApiError> {
    let b: Body =
        serde_json::from_slice(body).map_err(|e| ApiError::BadRequest(format!("spindle: {e}")))?;
    let direction = match b.direction.to_ascii_lowercase().as_str() {
        "cw" => SpindleDirection::Cw,
        "ccw" => SpindleDirection::Ccw,
        "stop" => SpindleDirection::Stop,
        other => {
            return Err(ApiError::BadRequest(format!(
                "spindle: the direction is \"cw\", \"ccw\" or \"stop\", not {other:?}"
            )));
        }
    };
    let speed = match (direction, b.speed) {
        (SpindleDirection::Stop, s) => s.unwrap_or(0.0),
        (_, Some(s)) => s,
        (_, None) => {
            return Err(ApiError::BadRequest(
                "spindle: turning it needs a speed (rpm)".into(),
            ));
        }
    };
    Ok(SpindleRequest { direction, speed })
}

/// Turns the spindle on, off or to another speed: 204 once commanded; 409 while a program
/// runs or a fault waits for Reset; 422 for a bad body, a speed outside the spindle's range
/// or a machine without a spindle the dashboard can turn.
pub(super) async fn spindle(
    State(app): State<App>,
    body: axum::body::Bytes,
) -> Result<StatusCode, ApiError> {
    let request = parse(&body)?;
    ask(&app, |r| Command::Spindle(request, r)).await
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bodies_are_read_or_refused_with_the_reason() {
        let ok = parse(br#"{"direction": "CW", "speed": 1200}"#).unwrap();
        assert_eq!((ok.direction, ok.speed), (SpindleDirection::Cw, 1200.0));
        let stop = parse(br#"{"direction": "stop"}"#).unwrap();
        assert_eq!(stop.direction, SpindleDirection::Stop);
        for bad in [
            &br#"{"direction": "left", "speed": 10}"#[..],
            br#"{"direction": "cw"}"#,
            br#"{"speed": 10}"#,
            br#"{"direction": "cw", "speed": "fast"}"#,
            b"not json",
        ] {
            assert!(
                matches!(parse(bad), Err(ApiError::BadRequest(_))),
                "{}",
                String::from_utf8_lossy(bad)
            );
        }
    }
}
