/*
 * errors.test.mjs - bad requests of every kind, each answered with its status and the error
 * object {"error": {"code", "message", "field"}}: code always, field and message exactly where
 * routes.h or the job format (job_json.h, tests/unit/test_job_json.c) fix them. Then the service
 * must still be healthy. Also the bearer token: POST and DELETE need it, GET does not.
 */
import assert from 'node:assert/strict';
import test from 'node:test';

import { BACKEND, startServer, submit, waitJob } from './lib.mjs';

const TOKEN = 's3cret';
const LONG = { preset: 'n_link_pendulum', n: 64, duration: 600, integrator: { method: 'rk4', step: 0.0001 }, output: { interval: 0.1 } };
const SHORT = { preset: 'triple_pendulum_pd', duration: 0.3 };

/* jobs as in tests/unit/test_job_json.c */
const REV = { type: 'revolute', axis: [0, 0, 1] };
const BODY = { mass: 1, com: [0, -0.5, 0], inertia: [0.1, 0.1, 0.1], joint: REV };
const BODY2 = { ...BODY, joint: { ...REV, location: [0, -1, 0] } };
const SCENE1 = { bodies: [BODY] };
const SCENE2 = { bodies: [BODY, BODY2] };
const PASSIVE = { type: 'none' };
const PD = { type: 'pd', kp: 100, kv: 20 };
const HOLD = { type: 'constant', value: 0 };
const passiveJob = (extra = {}) => ({ scene: SCENE2, controller: PASSIVE, duration: 1, ...extra });
const ctrlJob = (controller) => ({ scene: SCENE2, controller, trajectory: HOLD, duration: 1 });
const bodyJob = (body) => ({ scene: { bodies: [body] }, controller: PASSIVE, duration: 1 });
const unitBody = (extra) => ({ mass: 1, com: [0, 0, 0], inertia: [1, 1, 1], joint: REV, ...extra });

/* 65537 bodies, compact (about 6.4 MB) */
function tooManyBodies() {
    const b = JSON.stringify(BODY);
    return `{"scene":{"bodies":[${Array(65537).fill(b).join(',')}]},"controller":{"type":"none"},"duration":1}`;
}

const PASSWD = /root:.*:0:0:/;

/*
 * The table. Each case: name; method (POST); path (/api/jobs; {done}, {running} and {queued} are
 * replaced by ids); json or body (text, sent as application/json unless headers say otherwise);
 * headers; raw (send with node:http, byte for byte); server ('A': --max-body 64K, 'B': --token);
 * status; code; field (undefined: any string); message (string, RegExp, or undefined: any);
 * allow (methods the Allow header must list); passwd (the answer must not leak /etc/passwd).
 */
const J = 'application/json';
const CASES = [
    /* the body is not JSON, or not a job object */
    { name: 'empty body', body: '', status: 400, code: 'INVALID_JSON', field: '', message: 'empty document' },
    { name: 'white space only', body: ' \n\t ', status: 400, code: 'INVALID_JSON', field: '', message: 'empty document' },
    { name: 'truncated JSON', body: '{"scene":', status: 400, code: 'INVALID_JSON', field: '', message: 'invalid JSON at line 1, column 9' },
    { name: 'truncated preset request', body: '{"preset": "triple_pendulum_pd", "duration": 1', status: 400, code: 'INVALID_JSON', field: '', message: /^invalid JSON at line 1, column \d+/ },
    { name: 'malformed: trailing comma on line 3', body: '{\n  "duration": 1,\n  "scene": [1, 2,]\n}', status: 400, code: 'INVALID_JSON', field: '', message: 'invalid JSON at line 3, column 18' },
    { name: 'text after the document', body: '{} x', status: 400, code: 'INVALID_JSON', field: '', message: 'invalid JSON at line 1, column 4: text after the end of the document' },
    { name: 'bare NaN is not JSON', body: '{"preset": "triple_pendulum_pd", "duration": NaN}', status: 400, code: 'INVALID_JSON', field: '', message: /^invalid JSON at line 1, column \d+/ },
    /* RFC 8259 where cJSON is lenient (issue 25, defect 10) */
    { name: 'number with a leading zero', body: '{"preset":"triple_pendulum_pid","duration":01}', status: 400, code: 'INVALID_JSON', field: '', message: 'invalid JSON at line 1, column 44: a number must not have a leading zero' },
    { name: 'number ending in a decimal point', body: '{"preset":"triple_pendulum_pd","duration":1.}', status: 400, code: 'INVALID_JSON', field: '', message: 'invalid JSON at line 1, column 43: a decimal point must be followed by a digit' },
    { name: '\\u0000 in a string', body: '{"preset":"triple_pendulum_pd","name":"a\\u0000b"}', status: 400, code: 'INVALID_JSON', field: '', message: 'invalid JSON at line 1, column 41: a string must not hold \\u0000' },
    { name: 'JSON array body', body: '[1, 2]', status: 400, code: 'INVALID_FIELD', field: '', message: 'the job must be a JSON object (got an array)' },
    { name: 'JSON number body', body: '42', status: 400, code: 'INVALID_FIELD', field: '', message: 'the job must be a JSON object (got a number)' },
    { name: 'JSON string body', body: '"job"', status: 400, code: 'INVALID_FIELD', field: '', message: /^the job must be a JSON object \(got a string\)$/ },
    { name: 'repeated key', body: '{"duration":1,"duration":2}', status: 400, code: 'INVALID_FIELD', field: 'duration', message: 'key "duration" appears more than once' },

    /* the job's content */
    { name: 'empty object', json: {}, status: 400, code: 'MISSING_FIELD', field: 'scene', message: 'is required' },
    { name: 'misspelt key', json: passiveJob({ durration: 1 }), status: 400, code: 'UNKNOWN_FIELD', field: 'durration', message: 'unknown key "durration" (did you mean "duration"?)' },
    { name: 'unknown key', json: passiveJob({ colour: 'red' }), status: 400, code: 'UNKNOWN_FIELD', field: 'colour', message: 'unknown key "colour"' },
    { name: 'unknown key beside a preset', json: { preset: 'triple_pendulum_pd', colour: 'red' }, status: 400, code: 'UNKNOWN_FIELD', field: 'colour', message: 'unknown key "colour"' },
    { name: 'wrong type: name a number', json: passiveJob({ name: 5 }), status: 400, code: 'INVALID_FIELD', field: 'name', message: 'must be a string (got a number)' },
    { name: 'wrong type: duration a string', json: { scene: SCENE2, controller: PASSIVE, duration: '5' }, status: 400, code: 'INVALID_FIELD', field: 'duration', message: 'must be a number (got a string)' },
    { name: 'wrong type: scene an array', json: { scene: [], controller: PASSIVE, duration: 1 }, status: 400, code: 'INVALID_FIELD', field: 'scene', message: 'must be an object (got an array)' },
    { name: '"NaN" text as the mass', json: bodyJob(unitBody({ mass: 'NaN' })), status: 400, code: 'INVALID_FIELD', field: 'scene.bodies[0].mass', message: 'must be a number (got a string)' },
    { name: 'mass 1e999', body: JSON.stringify(bodyJob(unitBody({ mass: 12345 }))).replace('12345', '1e999'), status: 400, code: 'INVALID_FIELD', field: 'scene.bodies[0].mass', message: 'must be finite (got inf)' },
    { name: 'gravity -1e999', body: JSON.stringify({ scene: { ...SCENE2, gravity: [0, 12345, 0] }, controller: PASSIVE, duration: 1 }).replace('12345', '-1e999'), status: 400, code: 'INVALID_FIELD', field: 'scene.gravity[1]', message: 'must be finite (got -inf)' },
    { name: 'negative mass', json: bodyJob(unitBody({ mass: -1 })), status: 400, code: 'INVALID_FIELD', field: 'scene.bodies[0].mass', message: 'must not be negative (got -1 kg)' },
    { name: 'negative principal moment', json: bodyJob(unitBody({ inertia: [1, -1, 1] })), status: 400, code: 'INVALID_FIELD', field: 'scene.bodies[0].inertia[1]', message: 'must not be negative (got -1 kg m^2)' },
    { name: 'no bodies', json: { scene: { bodies: [] }, controller: PASSIVE, duration: 1 }, status: 400, code: 'INVALID_FIELD', field: 'scene.bodies', message: 'must not be empty' },
    { name: 'unknown joint type', json: bodyJob(unitBody({ joint: { type: 'hinge' } })), status: 400, code: 'INVALID_FIELD', field: 'scene.bodies[0].joint.type', message: 'must be one of "revolute", "prismatic", "cylindrical", "spherical", "fixed" (got "hinge")' },
    { name: 'no controller', json: { scene: SCENE1, duration: 1 }, status: 400, code: 'MISSING_FIELD', field: 'controller', message: 'is required ({"type": "none"} for a passive run)' },
    { name: 'no duration', json: { scene: SCENE1, controller: PASSIVE }, status: 400, code: 'MISSING_FIELD', field: 'duration', message: 'is required' },
    { name: 'unknown controller type', json: ctrlJob({ type: 'pdd' }), status: 400, code: 'INVALID_FIELD', field: 'controller.type', message: 'must be one of "none", "pd", "pid", "poles", "lqr", "joint_pd", "pd_gravity", "feedforward" (got "pdd")' },
    { name: 'kp without kv', json: ctrlJob({ type: 'pd', kp: 100 }), status: 400, code: 'MISSING_FIELD', field: 'controller.kv', message: 'is required with "kp"' },
    { name: 'unstable pid', json: ctrlJob({ type: 'pid', kp: 100, kv: 20, ki: 2000 }), status: 400, code: 'INVALID_FIELD', field: 'controller', message: 'ki = 2000 must be below kv*kp = 2000 (Routh-Hurwitz: the closed-loop error dynamics would be unstable)' },
    { name: 'controller without a trajectory', json: { scene: SCENE2, controller: PD, duration: 1 }, status: 400, code: 'MISSING_FIELD', field: 'trajectory', message: 'is required with controller "pd"' },
    { name: 'hopeless rk4 step 1e-300', json: passiveJob({ integrator: { method: 'rk4', step: 1e-300 } }), status: 400, code: 'INVALID_FIELD', field: 'integrator.step', message: 'duration / step = 1e+300 steps exceeds integrator.max_steps (10000000): use a larger step (got 1e-300 s for 1 s)' },
    { name: 'rk4 work of 4096 bodies for 1000 s', json: { preset: 'n_link_pendulum', n: 4096, duration: 1000, integrator: { method: 'rk4', step: 1e-4 } }, status: 400, code: 'LIMIT_EXCEEDED', field: 'integrator.step', message: "1e+07 steps x 4096 bodies = 4.1e+10 body-steps exceeds the bound on a job's work (1e+09): use a larger step, a shorter duration or fewer bodies (got 0.0001 s for 1000 s)" },
    { name: 'negative integrator min_step', json: passiveJob({ integrator: { method: 'bdf', min_step: -1 } }), status: 400, code: 'INVALID_FIELD', field: 'integrator', message: 'min_step must be >= 0 and finite (got -1 s)' },
    { name: 'unknown integrator method', json: passiveJob({ integrator: { method: 'euler' } }), status: 400, code: 'INVALID_FIELD', field: 'integrator.method', message: 'must be one of "rk4", "dopri5", "bdf" (got "euler")' },
    { name: 'unknown channel', json: passiveJob({ output: { channels: ['x'] } }), status: 400, code: 'INVALID_FIELD', field: 'output.channels[0]', message: 'must be one of "q", "qdot", "q_des", "qdot_des", "e", "tau", "w", "energy", "loop", "end_effector", "body_pose" (got "x")' },
    { name: 'two hours', json: { scene: SCENE2, controller: PASSIVE, duration: 7200 }, status: 400, code: 'LIMIT_EXCEEDED', field: 'duration', message: 'must be at most 3600 s (got 7200 s)' },
    { name: 'too many samples', json: { scene: SCENE2, controller: PASSIVE, duration: 3600 }, status: 400, code: 'LIMIT_EXCEEDED', field: 'output.interval', message: 'gives up to 360002 samples over 3600 s; the limit is 200000 (use a longer interval)' },
    { name: 'too many bodies (65537)', server: 'B', headers: { 'content-type': J, authorization: `Bearer ${TOKEN}` }, body: tooManyBodies(), status: 400, code: 'LIMIT_EXCEEDED', field: 'scene.bodies', message: 'has 65537 bodies; the limit is 65536' },

    /* presets in a body */
    { name: 'unknown preset', json: { preset: 'nope' }, status: 400, code: 'UNKNOWN_PRESET', field: 'preset', message: /^unknown preset "nope" \(the presets are: triple_pendulum_pd, .*n_link_pendulum, five_bar_pd, .*rssr_passive, y_pendulum_pd, y_four_bar_pd, spatial_hand_pd, two_arm_torso_pd, ur5_min_jerk, iiwa14_min_jerk, .*triple_pendulum_pid_limited, panda_min_jerk, two_link_min_jerk, two_link_lab_payload, puma560_min_jerk\)$/ },
    { name: 'loop between two branches', json: { preset: 'y_four_bar_pd', scene: { loop: { body: 3 } } }, status: 400, code: 'INVALID_FIELD', field: 'scene.loop', message: 'loop: body 3 is not on the path from the ground to the tip (body 5); a loop between two branches is not supported yet' },
    { name: 'preset not a string', json: { preset: 5 }, status: 400, code: 'INVALID_FIELD', field: 'preset', message: 'must be a string (got a number)' },
    { name: 'preset parameter out of range', json: { preset: 'n_link_pendulum', n: 1 }, status: 400, code: 'INVALID_FIELD', field: 'n', message: 'must be an integer from 2 to 65536 (got 1)' },
    { name: 'validate: negative mass', path: '/api/validate', json: bodyJob(unitBody({ mass: -1 })), status: 400, code: 'INVALID_FIELD', field: 'scene.bodies[0].mass', message: 'must not be negative (got -1 kg)' },
    { name: 'validate: array body', path: '/api/validate', body: '[]', status: 400, code: 'INVALID_FIELD', field: '', message: 'the job must be a JSON object (got an array)' },

    /* the HTTP envelope */
    { name: 'body over --max-body (100 KB > 64K)', body: `{"name": "${'x'.repeat(100 * 1024)}"}`, status: 413, code: 'BODY_TOO_LARGE' },
    { name: 'body over --max-body, Expect: 100-continue', raw: true, headers: { 'content-type': J, expect: '100-continue' }, body: `{"name": "${'x'.repeat(100 * 1024)}"}`, status: 413, code: 'BODY_TOO_LARGE' },
    { name: 'text/plain', headers: { 'content-type': 'text/plain' }, json: SHORT, status: 415, code: 'UNSUPPORTED_MEDIA_TYPE' },
    { name: 'form encoded', headers: { 'content-type': 'application/x-www-form-urlencoded' }, body: 'preset=triple_pendulum_pd', status: 415, code: 'UNSUPPORTED_MEDIA_TYPE' },
    { name: 'no content type', raw: true, headers: {}, body: JSON.stringify(SHORT), status: 415, code: 'UNSUPPORTED_MEDIA_TYPE' },
    { name: 'validate: text/plain', path: '/api/validate', headers: { 'content-type': 'text/plain' }, json: SHORT, status: 415, code: 'UNSUPPORTED_MEDIA_TYPE' },

    /* the server's own limit on a job's threads (server A: --job-threads 2) */
    { name: 'threads above --job-threads', json: { ...SHORT, threads: 3 }, status: 400, code: 'INVALID_FIELD', field: 'threads', message: /at most 2 on this server/ },
    { name: 'validate: threads above --job-threads', path: '/api/validate', json: { ...SHORT, threads: 3 }, status: 400, code: 'INVALID_FIELD', field: 'threads', message: /at most 2 on this server/ },

    /* routes and methods */
    { name: 'unknown route', method: 'GET', path: '/api/nope', status: 404, code: 'NOT_FOUND' },
    { name: 'unknown route below a job', method: 'GET', path: '/api/jobs/{done}/nope', status: 404, code: 'NOT_FOUND' },
    { name: 'PUT /api/jobs', method: 'PUT', path: '/api/jobs', json: SHORT, status: 405, code: 'METHOD_NOT_ALLOWED', allow: ['GET', 'POST'] },
    { name: 'DELETE /api/jobs', method: 'DELETE', path: '/api/jobs', status: 405, code: 'METHOD_NOT_ALLOWED', allow: ['GET', 'POST'] },
    { name: 'PATCH a job', method: 'PATCH', path: '/api/jobs/{done}', json: {}, status: 405, code: 'METHOD_NOT_ALLOWED', allow: ['GET', 'DELETE'] },
    { name: 'POST /api/health', method: 'POST', path: '/api/health', json: {}, status: 405, code: 'METHOD_NOT_ALLOWED', allow: ['GET'] },
    { name: 'DELETE /api/presets', method: 'DELETE', path: '/api/presets', status: 405, code: 'METHOD_NOT_ALLOWED', allow: ['GET'] },

    /* ids */
    { name: 'id abc', method: 'GET', path: '/api/jobs/abc', status: 400, code: 'INVALID_ID', field: 'id' },
    { name: 'id 0', method: 'GET', path: '/api/jobs/0', status: 400, code: 'INVALID_ID', field: 'id' },
    { name: 'id -1', method: 'GET', path: '/api/jobs/-1', status: 400, code: 'INVALID_ID', field: 'id' },
    { name: 'id 1.5', method: 'GET', path: '/api/jobs/1.5', status: 400, code: 'INVALID_ID', field: 'id' },
    { name: 'id over 2^64', method: 'GET', path: '/api/jobs/99999999999999999999', status: 400, code: 'INVALID_ID', field: 'id' },
    { name: 'DELETE id abc', method: 'DELETE', path: '/api/jobs/abc', status: 400, code: 'INVALID_ID', field: 'id' },
    { name: 'series of id 0', method: 'GET', path: '/api/jobs/0/series', status: 400, code: 'INVALID_ID', field: 'id' },
    { name: 'unknown id', method: 'GET', path: '/api/jobs/999999', status: 404, code: 'NOT_FOUND' },
    { name: 'DELETE unknown id', method: 'DELETE', path: '/api/jobs/999999', status: 404, code: 'NOT_FOUND' },
    { name: 'series of an unknown id', method: 'GET', path: '/api/jobs/999999/series', status: 404, code: 'NOT_FOUND' },
    { name: 'series of a running job', method: 'GET', path: '/api/jobs/{running}/series', status: 409, code: 'NOT_FINISHED' },
    { name: 'series of a queued job', method: 'GET', path: '/api/jobs/{queued}/series?format=csv', status: 409, code: 'NOT_FINISHED' },

    /* query parameters */
    { name: 'limit=0', method: 'GET', path: '/api/jobs?limit=0', status: 400, code: 'INVALID_QUERY', field: 'limit' },
    { name: 'limit=abc', method: 'GET', path: '/api/jobs?limit=abc', status: 400, code: 'INVALID_QUERY', field: 'limit' },
    { name: 'limit=201', method: 'GET', path: '/api/jobs?limit=201', status: 400, code: 'INVALID_QUERY', field: 'limit' },
    { name: 'limit=-1', method: 'GET', path: '/api/jobs?limit=-1', status: 400, code: 'INVALID_QUERY', field: 'limit' },
    { name: 'limit empty', method: 'GET', path: '/api/jobs?limit=', status: 400, code: 'INVALID_QUERY', field: 'limit' },
    { name: 'status=bogus', method: 'GET', path: '/api/jobs?status=bogus', status: 400, code: 'INVALID_QUERY', field: 'status' },
    { name: 'cursor=x', method: 'GET', path: '/api/jobs?cursor=x', status: 400, code: 'INVALID_QUERY', field: 'cursor' },
    { name: 'cursor=-5', method: 'GET', path: '/api/jobs?cursor=-5', status: 400, code: 'INVALID_QUERY', field: 'cursor' },
    { name: 'every=0', method: 'GET', path: '/api/jobs/{done}/series?every=0', status: 400, code: 'INVALID_QUERY', field: 'every' },
    { name: 'every=abc', method: 'GET', path: '/api/jobs/{done}/series?every=abc', status: 400, code: 'INVALID_QUERY', field: 'every' },
    { name: 'channels=bogus', method: 'GET', path: '/api/jobs/{done}/series?channels=bogus', status: 400, code: 'INVALID_QUERY', field: 'channels' },
    { name: 'channels=q,,tau', method: 'GET', path: '/api/jobs/{done}/series?channels=q,,tau', status: 400, code: 'INVALID_QUERY', field: 'channels' },
    { name: 'joints=99 (3 coordinates)', method: 'GET', path: '/api/jobs/{done}/series?joints=99', status: 400, code: 'INVALID_QUERY', field: 'joints' },
    { name: 'joints=3 (3 coordinates)', method: 'GET', path: '/api/jobs/{done}/series?joints=0,3', status: 400, code: 'INVALID_QUERY', field: 'joints' },
    { name: 'joints=a', method: 'GET', path: '/api/jobs/{done}/series?joints=a', status: 400, code: 'INVALID_QUERY', field: 'joints' },
    { name: 'format=xml', method: 'GET', path: '/api/jobs/{done}/series?format=xml', status: 400, code: 'INVALID_QUERY', field: 'format' },
    { name: 'wait=-1', path: '/api/jobs?wait=-1', json: SHORT, status: 400, code: 'INVALID_QUERY', field: 'wait' },
    { name: 'wait=0', path: '/api/jobs?wait=0', json: SHORT, status: 400, code: 'INVALID_QUERY', field: 'wait' },
    { name: 'wait=1000', path: '/api/jobs?wait=1000', json: SHORT, status: 400, code: 'INVALID_QUERY', field: 'wait' },
    { name: 'wait=abc', path: '/api/jobs?wait=abc', json: SHORT, status: 400, code: 'INVALID_QUERY', field: 'wait' },

    /* presets by path */
    { name: 'unknown preset path', method: 'GET', path: '/api/presets/nope', status: 404, code: 'UNKNOWN_PRESET' },
    { name: 'preset parameter n=1', method: 'GET', path: '/api/presets/n_link_pendulum?n=1', status: 400, code: 'INVALID_QUERY', field: 'n' },
    { name: 'preset parameter n=abc', method: 'GET', path: '/api/presets/n_link_pendulum?n=abc', status: 400, code: 'INVALID_QUERY', field: 'n' },
    { name: 'preset parameter n=70000', method: 'GET', path: '/api/presets/n_link_pendulum?n=70000', status: 400, code: 'INVALID_QUERY', field: 'n' },

    /* traversal out of the web root */
    { name: 'traversal /../etc/passwd', method: 'GET', raw: true, path: '/../etc/passwd', status: 404, passwd: true },
    { name: 'traversal /../../../../etc/passwd', method: 'GET', raw: true, path: '/../../../../etc/passwd', status: 404, passwd: true },
    { name: 'traversal /%2e%2e/%2e%2e/etc/passwd', method: 'GET', raw: true, path: '/%2e%2e/%2e%2e/etc/passwd', status: 404, passwd: true },
    { name: 'traversal /web/../../etc/passwd', method: 'GET', raw: true, path: '/web/../../etc/passwd', status: 404, passwd: true },
    { name: 'traversal /..%2fetc%2fpasswd', method: 'GET', raw: true, path: '/..%2fetc%2fpasswd', status: 404, passwd: true },
    { name: 'traversal /..%2f..%2f..%2fetc%2fpasswd', method: 'GET', raw: true, path: '/..%2f..%2f..%2fetc%2fpasswd', status: 404, passwd: true },
    { name: 'traversal /%2e%2e%2f%2e%2e%2fetc%2fpasswd', method: 'GET', raw: true, path: '/%2e%2e%2f%2e%2e%2fetc%2fpasswd', status: 404, passwd: true },
    { name: 'absolute path //etc/passwd', method: 'GET', raw: true, path: '//etc/passwd', status: 404, passwd: true },
];

const servers = {};
const ids = {};

test('the servers start (A: --max-body 64K --job-threads 2, B: --token)', async () => {
    servers.A = await startServer({ workers: 2, args: ['--max-body', '64K', '--job-threads', '2'] });
    servers.B = await startServer({ workers: 1, args: ['--token', TOKEN] });
});

test('setup: a finished job, two running and one queued', async () => {
    const A = servers.A;
    ids.done = (await submit(A, SHORT)).id;
    assert.equal((await waitJob(A, ids.done)).status, 'done');
    ids.running = (await submit(A, LONG)).id;
    ids.running2 = (await submit(A, LONG)).id;
    ids.queued = (await submit(A, LONG)).id;
});

test(`the table has at least 40 bad requests (${CASES.length})`, () => {
    assert.ok(CASES.length >= 40);
});

for (const c of CASES) {
    const method = c.method || 'POST';
    const label = `${method} ${c.path || '/api/jobs'}: ${c.name} -> ${c.status}${c.code ? ` ${c.code}` : ''}`;
    test(label, async () => {
        const srv = servers[c.server || 'A'];
        const urlPath = (c.path || '/api/jobs').replace(/\{(\w+)\}/g, (_, k) => String(ids[k]));
        let headers = c.headers;
        if (!headers && (c.json !== undefined || c.body !== undefined)) headers = { 'content-type': J };
        const body = c.json !== undefined ? JSON.stringify(c.json) : c.body;
        const res = c.raw
            ? await srv.raw(method, urlPath, { headers, body })
            : await srv.request(method, urlPath, { headers, body });
        const what = `${method} ${urlPath} -> ${res.status} ${res.text.slice(0, 300)}`;
        assert.equal(res.status, c.status, what);
        if (c.passwd) {
            assert.doesNotMatch(res.text, PASSWD, 'the answer leaks /etc/passwd');
            if (res.json?.error) assert.equal(res.json.error.code, 'NOT_FOUND', what);
            return;
        }
        assert.match(res.headers['content-type'] || '', /^application\/json/, what);
        const err = res.json?.error;
        assert.ok(err && typeof err === 'object', `no error object: ${what}`);
        assert.equal(err.code, c.code, what);
        assert.equal(typeof err.field, 'string', what);
        assert.equal(typeof err.message, 'string', what);
        assert.ok(err.message.length > 0, what);
        if (c.field !== undefined) assert.equal(err.field, c.field, what);
        if (typeof c.message === 'string') assert.equal(err.message, c.message, what);
        else if (c.message) assert.match(err.message, c.message, what);
        if (c.allow) {
            const allow = (res.headers.allow || '').split(',').map((m) => m.trim()).filter(Boolean);
            assert.deepEqual([...allow].sort(), [...c.allow].sort(), `Allow: ${res.headers.allow}`);
        }
    });
}

test('a body just under --max-body (60 KB of white space) is accepted', async () => {
    const body = JSON.stringify(SHORT) + ' '.repeat(60 * 1024);
    const res = await servers.A.request('POST', '/api/jobs', { headers: { 'content-type': J }, body });
    assert.equal(res.status, 202, res.text);
});

test('a job asking for as many threads as --job-threads is accepted', async () => {
    const res = await servers.A.post('/api/jobs', { ...SHORT, threads: 2 });
    assert.equal(res.status, 202, res.text);
});

test('application/json with a charset is accepted', async () => {
    const res = await servers.A.request('POST', '/api/jobs', {
        headers: { 'content-type': 'application/json; charset=utf-8' },
        body: JSON.stringify(SHORT),
    });
    assert.equal(res.status, 202, res.text);
});

test('after all of them the service is healthy and counts the jobs it took', async () => {
    const res = await servers.A.get('/api/health');
    assert.equal(res.status, 200, res.text);
    assert.equal(res.json.status, 'ok');
    assert.deepEqual(res.json.database, { state: 'ok' });
    /* a PostgreSQL cluster's API process runs no workers itself (its worker processes do) */
    assert.equal(res.json.workers, BACKEND === 'postgres' ? 0 : 2);
    /* done, 3 long ones, 3 accepted above: no bad request was stored */
    const total = Object.values(res.json.jobs).reduce((a, b) => a + b, 0);
    assert.equal(total, 7, JSON.stringify(res.json.jobs));
});

test('the long jobs are cancelled: queued 200, running 202', async () => {
    const A = servers.A;
    const q = await A.del(`/api/jobs/${ids.queued}`);
    assert.ok(q.status === 200 || q.status === 202, q.text);
    for (const id of [ids.running, ids.running2]) {
        const r = await A.del(`/api/jobs/${id}`);
        assert.ok(r.status === 202 || r.status === 200, r.text);
    }
    for (const id of [ids.queued, ids.running, ids.running2]) {
        assert.equal((await waitJob(A, id, { timeoutMs: 5000 })).status, 'cancelled');
    }
});

test('a full queue: 503 QUEUE_FULL with Retry-After, and the job is not stored', async () => {
    const C = await startServer({ workers: 1, args: ['--max-queue', '1'] });
    try {
        const running = (await submit(C, LONG)).id;
        await waitJob(C, running, { until: (j) => j.status === 'running' });
        const waiting = (await submit(C, LONG)).id;
        const res = await C.post('/api/jobs', SHORT);
        assert.equal(res.status, 503, res.text);
        assert.equal(res.json.error.code, 'QUEUE_FULL');
        assert.ok(Number(res.headers['retry-after']) >= 1, `Retry-After: ${res.headers['retry-after']}`);
        const rows = (await C.get('/api/jobs')).json.jobs;
        assert.deepEqual(rows.map((r) => r.id), [waiting, running]);
        for (const id of [waiting, running]) assert.ok([200, 202].includes((await C.del(`/api/jobs/${id}`)).status));
    } finally {
        const r = await C.stop('SIGTERM');
        assert.equal(r.code, 0, C.output());
    }
});

/* ---- the token ---- */

test('--token: POST without Authorization is 401 UNAUTHORIZED', async () => {
    const res = await servers.B.post('/api/jobs', SHORT);
    assert.equal(res.status, 401, res.text);
    assert.equal(res.json.error.code, 'UNAUTHORIZED');
    const v = await servers.B.post('/api/validate', SHORT);
    assert.equal(v.status, 401, v.text);
    assert.equal(v.json.error.code, 'UNAUTHORIZED');
});

test('--token: POST with a wrong token or scheme is 401', async () => {
    for (const auth of ['Bearer wrong', `Bearer ${TOKEN}x`, `Basic ${TOKEN}`, TOKEN, 'Bearer ', `Bearer  ${TOKEN.slice(1)}`]) {
        const res = await servers.B.post('/api/jobs', SHORT, { authorization: auth });
        assert.equal(res.status, 401, `${auth}: ${res.text}`);
        assert.equal(res.json.error.code, 'UNAUTHORIZED');
    }
});

test('--token: auth comes before validation (a bad body without the token is 401)', async () => {
    const res = await servers.B.request('POST', '/api/jobs', { headers: { 'content-type': J }, body: '{' });
    assert.equal(res.status, 401, res.text);
});

test('--token: POST with the token is 202, GET needs none, DELETE needs it', async () => {
    const B = servers.B;
    const auth = { authorization: `Bearer ${TOKEN}` };
    const res = await B.post('/api/jobs', SHORT, auth);
    assert.equal(res.status, 202, res.text);
    const id = res.json.id;
    const v = await B.post('/api/validate', SHORT, auth);
    assert.equal(v.status, 200, v.text);
    assert.equal((await B.get('/api/jobs')).status, 200);
    assert.equal((await B.get('/api/health')).status, 200);
    assert.equal((await B.get('/api/presets')).status, 200);
    assert.equal((await waitJob(B, id)).status, 'done');
    assert.equal((await B.get(`/api/jobs/${id}/series?format=csv`)).status, 200);
    const d1 = await B.del(`/api/jobs/${id}`);
    assert.equal(d1.status, 401, d1.text);
    assert.equal(d1.json.error.code, 'UNAUTHORIZED');
    const d2 = await B.del(`/api/jobs/${id}`, { authorization: 'Bearer nope' });
    assert.equal(d2.status, 401, d2.text);
    const d3 = await B.del(`/api/jobs/${id}`, auth);
    assert.equal(d3.status, 204, d3.text);
    assert.equal((await B.get(`/api/jobs/${id}`)).status, 404);
});

test('the servers stop cleanly on SIGTERM', async () => {
    for (const srv of [servers.A, servers.B]) {
        const r = await srv.stop('SIGTERM');
        assert.equal(r.killed, undefined, `it had to be killed\n${srv.output()}`);
        assert.equal(r.code, 0, srv.output());
    }
});
