// SPDX-License-Identifier: MIT
// The installed Java types (share/java/sfd-lcmtypes.jar with Debian's lcm.jar): decodes the
// message that verdict_roundtrip wrote (the constructor checks the fingerprint) and checks its
// fields. javac -cp sfd-lcmtypes.jar:/usr/share/java/lcm.jar VerdictRead.java
import java.nio.file.Files;
import java.nio.file.Paths;

public class VerdictRead {
    public static void main(String[] args) throws Exception {
        sfd.feature_verdict_t m = new sfd.feature_verdict_t(Files.readAllBytes(Paths.get(args[0])));
        boolean ok = m.utime == 1234567 && m.camera_id == 1 && m.num_features == 3
                && m.track_id[1] == 12 && m.status[1] == sfd.feature_verdict_t.SPURIOUS
                && m.statistic[1] == 3.25 && m.stage[0] == sfd.feature_verdict_t.PARITY;
        System.out.println("Java sfd.feature_verdict_t: decoded: " + (ok ? "ok" : "WRONG"));
        System.exit(ok ? 0 : 1);
    }
}
