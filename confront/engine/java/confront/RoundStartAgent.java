package confront;

import java.io.ByteArrayOutputStream;
import java.io.DataOutputStream;
import java.io.IOException;
import java.lang.instrument.ClassFileTransformer;
import java.lang.instrument.Instrumentation;
import java.nio.charset.StandardCharsets;
import java.security.ProtectionDomain;
import java.util.concurrent.atomic.AtomicBoolean;

/**
 * Java agent that removes the engine's lost wake-up at round start (every robot, sample or ours).
 *
 * RobotPeer.startRound starts the robot's thread and then waits on the robot's "sleeping" monitor for its
 * first action, without first testing whether the robot is asleep already; a robot whose first action comes
 * before that wait loses the wake-up and the battle thread waits its full time-out (min(300 x CPU constant,
 * 10 s)). This agent rewrites, in RobotPeer only, the calls {@code Object.wait(long, int)} into
 * {@link #waitUnlessAsleep}, which returns at once when the monitor is an AtomicBoolean that is already
 * true (the robot is asleep). The engine's other timed waits in RobotPeer (waitSleeping) already test the
 * flag before each wait, so for them nothing changes.
 */
public final class RoundStartAgent implements ClassFileTransformer {
    private static final String TARGET = "net/sf/robocode/battle/peer/RobotPeer";
    /** Calls rewritten in the last transformed class (for the log line and the tests). */
    static volatile int rewritten = -1;

    private RoundStartAgent() {
    }

    /** Installs the transformer; the runner's class path (the compiled classes) also serves waitUnlessAsleep
     *  to the engine's own class loader, which asks its parent for classes outside the engine. */
    public static void premain(String args, Instrumentation inst) {
        inst.addTransformer(new RoundStartAgent());
    }

    /** Object.wait(ms, ns), skipped when the monitor is an AtomicBoolean already set (robot asleep). */
    public static void waitUnlessAsleep(Object monitor, long millis, int nanos) throws InterruptedException {
        if (monitor instanceof AtomicBoolean && ((AtomicBoolean) monitor).get()) {
            return;
        }
        monitor.wait(millis, nanos);
    }

    @Override
    public byte[] transform(ClassLoader loader, String name, Class<?> cls, ProtectionDomain pd, byte[] bytes) {
        if (!TARGET.equals(name)) {
            return null;
        }
        try {
            byte[] out = rewrite(bytes);
            System.err.println("RoundStartAgent: " + rewritten + " timed wait(s) in RobotPeer rewritten");
            return out;
        } catch (IOException | RuntimeException e) {
            System.err.println("RoundStartAgent: RobotPeer left unchanged: " + e);
            return null;
        }
    }

    /** The class with every invokevirtual Object.wait(JI)V turned into invokestatic waitUnlessAsleep. */
    static byte[] rewrite(byte[] b) throws IOException {
        int count = u2(b, 8);
        int[] offsets = new int[count];
        int p = 10;
        for (int i = 1; i < count; i++) {
            offsets[i] = p;
            int tag = b[p] & 0xff;
            switch (tag) {
                case 1: p += 3 + u2(b, p + 1); break;                      // Utf8
                case 3: case 4: case 9: case 10: case 11: case 12: case 17: case 18: p += 5; break;
                case 5: case 6: p += 9; i++; break;                        // Long, Double take two slots
                case 7: case 8: case 16: case 19: case 20: p += 3; break;
                case 15: p += 4; break;                                    // MethodHandle
                default: throw new IOException("unknown constant tag " + tag);
            }
        }
        int poolEnd = p;
        int waitRef = -1;
        int codeName = -1;
        for (int i = 1; i < count; i++) {
            int o = offsets[i];
            if (o != 0 && (b[o] & 0xff) == 1 && "Code".equals(utf(b, offsets, i))) {
                codeName = i;
            }
            if (o == 0 || (b[o] & 0xff) != 10) {
                continue;
            }
            int nat = offsets[u2(b, o + 3)];
            if ("java/lang/Object".equals(utf(b, offsets, u2(b, offsets[u2(b, o + 1)] + 1)))
                    && "wait".equals(utf(b, offsets, u2(b, nat + 1)))
                    && "(JI)V".equals(utf(b, offsets, u2(b, nat + 3)))) {
                waitRef = i;
            }
        }
        if (waitRef < 0) {
            rewritten = 0;
            return null;
        }
        // new constants: Utf8 class, Class, Utf8 name, Utf8 descriptor, NameAndType, Methodref
        ByteArrayOutputStream extra = new ByteArrayOutputStream();
        DataOutputStream d = new DataOutputStream(extra);
        int c = count;
        d.writeByte(1);
        d.writeUTF("confront/RoundStartAgent");
        d.writeByte(7);
        d.writeShort(c);
        d.writeByte(1);
        d.writeUTF("waitUnlessAsleep");
        d.writeByte(1);
        d.writeUTF("(Ljava/lang/Object;JI)V");
        d.writeByte(12);
        d.writeShort(c + 2);
        d.writeShort(c + 3);
        d.writeByte(10);
        d.writeShort(c + 1);
        d.writeShort(c + 4);
        int newRef = c + 5;
        byte[] rest = java.util.Arrays.copyOfRange(b, poolEnd, b.length);
        int n = rewriteCalls(rest, codeName, waitRef, newRef);
        rewritten = n;
        ByteArrayOutputStream all = new ByteArrayOutputStream();
        all.write(b, 0, 8);
        all.write((count + 6) >> 8);
        all.write((count + 6) & 0xff);
        all.write(b, 10, poolEnd - 10);
        all.write(extra.toByteArray());
        all.write(rest);
        return all.toByteArray();
    }

    /** In the methods' Code attributes of the class body after the constant pool, replace the calls. */
    private static int rewriteCalls(byte[] r, int codeName, int waitRef, int newRef) {
        int p = 6;                                         // access, this, super
        p += 2 + 2 * u2(r, p);                             // interfaces
        int fields = u2(r, p);
        p += 2;
        for (int f = 0; f < fields; f++) {
            p = skipMember(r, p);
        }
        int methods = u2(r, p);
        p += 2;
        int n = 0;
        for (int m = 0; m < methods; m++) {
            int attrs = u2(r, p + 6);
            int a = p + 8;
            for (int k = 0; k < attrs; k++) {
                int len = u4(r, a + 2);
                if (u2(r, a) == codeName) {                // Code: max_stack, max_locals, code_length, code
                    n += replaceInvokes(r, a + 14, a + 14 + u4(r, a + 10), waitRef, newRef);
                }
                a += 6 + len;
            }
            p = a;
        }
        return n;
    }

    /** Replaces each invokevirtual #waitRef in code[start, end); returns how many. */
    private static int replaceInvokes(byte[] r, int start, int end, int waitRef, int newRef) {
        int n = 0;
        for (int q = start; q + 2 < end; q++) {
            if ((r[q] & 0xff) == 0xb6 && u2(r, q + 1) == waitRef) {
                r[q] = (byte) 0xb8;
                r[q + 1] = (byte) (newRef >> 8);
                r[q + 2] = (byte) newRef;
                n++;
                q += 2;
            }
        }
        return n;
    }

    private static int skipMember(byte[] r, int p) {
        int attrs = u2(r, p + 6);
        p += 8;
        for (int k = 0; k < attrs; k++) {
            p += 6 + u4(r, p + 2);
        }
        return p;
    }

    private static String utf(byte[] b, int[] offsets, int index) {
        int o = offsets[index];
        return new String(b, o + 3, u2(b, o + 1), StandardCharsets.UTF_8);
    }

    private static int u2(byte[] b, int p) {
        return ((b[p] & 0xff) << 8) | (b[p + 1] & 0xff);
    }

    private static int u4(byte[] b, int p) {
        return (u2(b, p) << 16) | u2(b, p + 2);
    }
}
