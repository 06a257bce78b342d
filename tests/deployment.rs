//! The container files, checked by reading: no Docker engine runs where
//! the tests do.

/// A database password with '@', '/' or ':' broke `MPM_DATABASE`'s URL:
/// the password goes in `PGPASSWORD` (which sqlx reads when the URL has
/// none), never in the URL.
#[test]
fn compose_keeps_the_database_password_out_of_the_url() {
    let compose: serde_yaml::Value =
        serde_yaml::from_str(include_str!("../docker-compose.yml")).unwrap();
    let mut checked = 0;
    for (name, service) in compose["services"].as_mapping().unwrap() {
        let env = &service["environment"];
        let Some(url) = env["MPM_DATABASE"].as_str() else {
            continue;
        };
        let user_info = url
            .split_once("://")
            .and_then(|(_, rest)| rest.split_once('@'))
            .map(|(user_info, _)| user_info);
        assert!(
            user_info.is_some_and(|u| !u.contains(':')),
            "{name:?}: {url}"
        );
        assert_eq!(
            env["PGPASSWORD"].as_str(),
            Some("${POSTGRES_PASSWORD}"),
            "{name:?}"
        );
        checked += 1;
    }
    assert_eq!(checked, 2, "the api and the worker");
}

/// Each worker container got an anonymous `/data` volume of its own from
/// the image's VOLUME; the health check ran through a shell.
#[test]
fn the_image_declares_no_volume_and_checks_health_in_exec_form() {
    let dockerfile = include_str!("../Dockerfile");
    let instructions: Vec<&str> = dockerfile
        .lines()
        .filter(|l| !l.trim_start().starts_with('#'))
        .collect();
    assert!(!instructions.iter().any(|l| l.starts_with("VOLUME")));
    let health = dockerfile
        .split("HEALTHCHECK")
        .nth(1)
        .expect("a HEALTHCHECK");
    let command = health.split("CMD").nth(1).unwrap().trim_start();
    assert!(command.starts_with("[\"curl\""), "{command}");
}
