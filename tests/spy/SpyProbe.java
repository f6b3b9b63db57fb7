// Runs lcm-spy (lcm.spy.Spy, with the class path findmug-spy uses) in this JVM, waits while
// messages arrive, then prints the spy's channel table, one row per line, cells separated
// by tabs, as the spy shows them (channel, type, ...). Used by spy_test.sh.
import java.awt.Component;
import java.awt.Container;
import java.awt.Frame;
import javax.swing.JTable;
import javax.swing.SwingUtilities;

public class SpyProbe {
  static JTable findTable(Component c) {
    if (c instanceof JTable) return (JTable) c;
    if (c instanceof Container) {
      for (Component child : ((Container) c).getComponents()) {
        JTable t = findTable(child);
        if (t != null) return t;
      }
    }
    return null;
  }

  public static void main(String[] args) throws Exception {
    long waitMs = Long.parseLong(args[0]);
    String[] spyArgs = java.util.Arrays.copyOfRange(args, 1, args.length);
    lcm.spy.Spy.main(spyArgs);
    Thread.sleep(waitMs);
    SwingUtilities.invokeAndWait(() -> {
      for (Frame f : Frame.getFrames()) {
        JTable table = findTable(f);
        if (table == null) continue;
        StringBuilder header = new StringBuilder("#");
        for (int c = 0; c < table.getColumnCount(); c++) header.append('\t').append(table.getColumnName(c));
        System.out.println(header);
        for (int r = 0; r < table.getRowCount(); r++) {
          StringBuilder row = new StringBuilder();
          for (int c = 0; c < table.getColumnCount(); c++) {
            if (c > 0) row.append('\t');
            row.append(String.valueOf(table.getValueAt(r, c)));
          }
          System.out.println(row);
        }
      }
    });
    System.out.flush();
    System.exit(0);
  }
}
