-- A service database as written by the service before Alembic (issue 47): SQLAlchemy create_all of
-- service/core/db.py at commit 290b53e, with two jobs, three diagnoses of one asset, its baseline and thresholds.
BEGIN TRANSACTION;
CREATE TABLE asset_baselines (
	asset_id VARCHAR(128) NOT NULL, 
	created_at DATETIME NOT NULL, 
	source VARCHAR(16) NOT NULL, 
	diagnosis_ids JSON NOT NULL, 
	recorded_at DATETIME, 
	speed_rpm FLOAT, 
	model_version VARCHAR(128) NOT NULL, 
	signature JSON NOT NULL, 
	repeatability JSON, 
	PRIMARY KEY (asset_id)
);
INSERT INTO "asset_baselines" VALUES('unit-7','2026-11-01 12:00:00.000000','diagnosis','[1, 2]','2026-11-01 12:00:00.000000',1800.0,'v0001','{"x1_amp_um_pp": 40.0}','null');
CREATE TABLE asset_diagnoses (
	id INTEGER NOT NULL, 
	asset_id VARCHAR(128) NOT NULL, 
	plant VARCHAR(128), 
	created_at DATETIME NOT NULL, 
	model_version VARCHAR(128) NOT NULL, 
	severity VARCHAR(32) NOT NULL, 
	misalignment FLOAT, 
	misalignment_low FLOAT, 
	misalignment_high FLOAT, 
	speed_rpm FLOAT, 
	ood BOOLEAN, 
	verdict JSON NOT NULL, 
	key_features JSON NOT NULL, 
	signature JSON, 
	change JSON, 
	alarm BOOLEAN, 
	PRIMARY KEY (id)
);
INSERT INTO "asset_diagnoses" VALUES(1,'unit-7','north','2026-11-01 12:00:00.000000','v0001','moderate',0.2,0.1,0.3,1800.0,0,'{"severity": "moderate", "misalignment": 0.2}','{"h2_ratio": 0.5}','{"x1_amp_um_pp": 40.0}',NULL,NULL);
INSERT INTO "asset_diagnoses" VALUES(2,'unit-7','north','2026-11-01 13:00:00.000000','v0001','moderate',2.10000000000000019984e-01,0.1,0.3,1800.0,0,'{"severity": "moderate", "misalignment": 0.21000000000000002}','{"h2_ratio": 0.5}','{"x1_amp_um_pp": 41.0}',NULL,NULL);
INSERT INTO "asset_diagnoses" VALUES(3,'unit-7','north','2026-11-01 14:00:00.000000','v0001','moderate',0.22,0.1,0.3,1800.0,0,'{"severity": "moderate", "misalignment": 0.22}','{"h2_ratio": 0.5}','{"x1_amp_um_pp": 42.0}','{"compared": true, "changed": true}',1);
CREATE TABLE asset_settings (
	asset_id VARCHAR(128) NOT NULL, 
	thresholds JSON NOT NULL, 
	updated_at DATETIME NOT NULL, 
	PRIMARY KEY (asset_id)
);
INSERT INTO "asset_settings" VALUES('unit-7','{"x1_amp_rel": 0.3}','2026-11-01 12:00:00.000000');
CREATE TABLE jobs (
	id VARCHAR(36) NOT NULL, 
	kind VARCHAR(16) NOT NULL, 
	status VARCHAR(16) NOT NULL, 
	params JSON NOT NULL, 
	progress FLOAT NOT NULL, 
	stage VARCHAR(64) NOT NULL, 
	message TEXT NOT NULL, 
	result JSON, 
	error TEXT, 
	attempts INTEGER NOT NULL, 
	created_at DATETIME NOT NULL, 
	started_at DATETIME, 
	finished_at DATETIME, 
	updated_at DATETIME NOT NULL, 
	PRIMARY KEY (id)
);
INSERT INTO "jobs" VALUES('00000000-0000-0000-0000-000000000001','dataset','succeeded','{"spec_toml": "x", "name": "a"}',1.0,'done','finished','{"n_samples": 16}',NULL,1,'2026-11-01 12:00:00.000000','2026-11-01 12:00:00.000000','2026-11-01 12:00:00.000000','2026-11-01 12:00:00.000000');
INSERT INTO "jobs" VALUES('00000000-0000-0000-0000-000000000002','retrain','interrupted','{"spec_toml": "y"}',0.4,'simulating','the server stopped',NULL,NULL,1,'2026-11-01 12:00:00.000000',NULL,NULL,'2026-11-01 12:00:00.000000');
CREATE INDEX ix_jobs_kind ON jobs (kind);
CREATE INDEX ix_jobs_status ON jobs (status);
CREATE INDEX ix_asset_diagnoses_asset_id ON asset_diagnoses (asset_id);
CREATE INDEX ix_asset_diagnoses_created_at ON asset_diagnoses (created_at);
COMMIT;
