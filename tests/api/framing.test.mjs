/*
 * framing.test.mjs - the service refuses requests whose body framing is ambiguous (issue 25,
 * defect 9), on the wire: raw bytes over a TCP socket, since node:http and fetch would refuse to
 * send such requests. Two Content-Length headers (equal or not), Content-Length with
 * Transfer-Encoding, two Transfer-Encoding headers and a Content-Length that is not a number are
 * answered 400 at once, and a transfer coding other than chunked 501 at once, each before the
 * handler runs and with the connection closed after the reply, so that the bytes after the headers
 * never start a second request. Well-framed requests (one Content-Length, or chunked) still pass.
 */
import assert from 'node:assert/strict';
import net from 'node:net';
import test from 'node:test';

import { startServer } from './lib.mjs';

let srv;

test('the server starts', async () => {
    srv = await startServer({ workers: 1 });
});

const BODY = '{"preset":"triple_pendulum_pd","duration":0.1}';

/* Sends raw (a string) and reads until the server closes or ms pass. Resolves {text, ms,
 * closed}: what came back, when the last byte or the close came, whether the server closed. */
function exchange(port, raw, ms = 3000) {
    return new Promise((resolve, reject) => {
        const sock = net.connect(port, '127.0.0.1');
        const chunks = [];
        const t0 = Date.now();
        let done = false;
        const finish = (closed) => {
            if (done) return;
            done = true;
            clearTimeout(timer);
            sock.destroy();
            resolve({ text: Buffer.concat(chunks).toString('latin1'), ms: Date.now() - t0, closed });
        };
        const timer = setTimeout(() => finish(false), ms);
        sock.on('connect', () => sock.write(raw));
        sock.on('data', (c) => chunks.push(c));
        sock.on('end', () => finish(true));
        sock.on('close', () => finish(true));
        sock.on('error', (e) => (chunks.length ? finish(true) : reject(e)));
    });
}

/* The first response in text: {status, headers (lower-case names, arrays), body}. */
function parseResponse(text) {
    const end = text.indexOf('\r\n\r\n');
    assert.ok(end > 0, `no header block in ${JSON.stringify(text)}`);
    const lines = text.slice(0, end).split('\r\n');
    const status = Number(/^HTTP\/1\.1 ([0-9]{3}) /.exec(lines[0])?.[1]);
    const headers = {};
    for (const line of lines.slice(1)) {
        const colon = line.indexOf(':');
        const name = line.slice(0, colon).toLowerCase();
        (headers[name] ||= []).push(line.slice(colon + 1).trim());
    }
    return { status, headers, body: text.slice(end + 4) };
}

function post(headers, body = BODY) {
    return `POST /api/validate HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n${headers.join('\r\n')}\r\n\r\n${body}`;
}

const chunked = `${BODY.length.toString(16)}\r\n${BODY}\r\n0\r\n\r\n`;

/* each refused request, and what the reply must say; a second request follows the first on the
   same connection, which must never be answered */
const refused = [
    {
        what: 'two differing Content-Length headers',
        raw: post([`Content-Length: ${BODY.length}`, 'Content-Length: 5']),
        status: 400, code: 'BAD_FRAMING', field: 'Content-Length',
        message: 'the request has 2 Content-Length headers; one is allowed',
    },
    {
        what: 'two equal Content-Length headers',
        raw: post([`Content-Length: ${BODY.length}`, `Content-Length: ${BODY.length}`]),
        status: 400, code: 'BAD_FRAMING', field: 'Content-Length',
        message: 'the request has 2 Content-Length headers; one is allowed',
    },
    {
        what: 'Content-Length with Transfer-Encoding: chunked',
        raw: post([`Content-Length: ${BODY.length}`, 'Transfer-Encoding: chunked'], chunked),
        status: 400, code: 'BAD_FRAMING', field: 'Transfer-Encoding',
        message: 'the request has both Content-Length and Transfer-Encoding; send one of them',
    },
    {
        what: 'two Transfer-Encoding headers',
        raw: post(['Transfer-Encoding: chunked', 'Transfer-Encoding: chunked'], chunked),
        status: 400, code: 'BAD_FRAMING', field: 'Transfer-Encoding',
        message: 'the request has 2 Transfer-Encoding headers; one is allowed',
    },
    {
        what: 'Transfer-Encoding: gzip',
        raw: post(['Transfer-Encoding: gzip'], BODY),
        status: 501, code: 'UNSUPPORTED_TRANSFER_ENCODING', field: 'Transfer-Encoding',
        message: 'Transfer-Encoding "gzip" is not supported (only chunked is)',
    },
    {
        what: 'Transfer-Encoding: gzip, chunked',
        raw: post(['Transfer-Encoding: gzip, chunked'], chunked),
        status: 501, code: 'UNSUPPORTED_TRANSFER_ENCODING', field: 'Transfer-Encoding',
        message: 'Transfer-Encoding "gzip, chunked" is not supported (only chunked is)',
    },
    {
        what: 'two Content-Length headers on a GET',
        raw: 'GET /api/health HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 3\r\nContent-Length: 4\r\n\r\nabcd',
        status: 400, code: 'BAD_FRAMING', field: 'Content-Length',
        message: 'the request has 2 Content-Length headers; one is allowed',
    },
];

for (const c of refused) {
    test(`${c.what}: ${c.status} ${c.code} at once, and the connection closed`, async () => {
        const smuggled = 'GET /api/health HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n';
        const r = await exchange(srv.port, c.raw + smuggled);
        assert.ok(r.closed, `the connection stayed open: ${JSON.stringify(r.text)}`);
        assert.ok(r.ms < 2000, `answered after ${r.ms} ms`);
        const res = parseResponse(r.text);
        assert.equal(res.status, c.status, r.text);
        assert.deepEqual(res.headers.connection, ['close']);
        assert.deepEqual(res.headers['content-type'], ['application/json']);
        assert.equal(res.headers['content-length'].length, 1);
        assert.equal(res.body, `${JSON.stringify({ error: { code: c.code, message: c.message, field: c.field } })}\n`);
        /* one reply only: the smuggled request was never answered */
        assert.equal(r.text.split('HTTP/1.1 ').length, 2, r.text);
    });
}

test('a Content-Length that is not a decimal number is refused at once and the connection closed', async () => {
    /* libmicrohttpd answers these itself, before the access handler (http.c, framing_refused) */
    for (const value of ['12x', '-5', `+${BODY.length}`, '99999999999999999999999']) {
        const r = await exchange(srv.port, post([`Content-Length: ${value}`]));
        assert.ok(r.closed && r.ms < 2000, `Content-Length: ${value}: ${JSON.stringify(r.text)}`);
        const res = parseResponse(r.text);
        assert.ok(res.status === 400 || res.status === 413, `Content-Length: ${value}: ${r.text}`);
        assert.deepEqual(res.headers.connection, ['close']);
    }
});

test('well-framed requests still pass: one Content-Length, or chunked, two on one connection', async () => {
    const one = post([`Content-Length: ${BODY.length}`]);
    const two = post(['Transfer-Encoding: chunked', 'Connection: close'], chunked);
    const r = await exchange(srv.port, one + two);
    const replies = r.text.split(/(?=HTTP\/1\.1 )/);
    assert.equal(replies.length, 2, r.text);
    for (const text of replies) {
        const res = parseResponse(text);
        assert.equal(res.status, 200, text);
        assert.equal(JSON.parse(res.body).valid, true);
    }
});

test('the server stops cleanly', async () => {
    const r = await srv.stop();
    assert.equal(r.code, 0, srv.output());
});
